"""Files written whole or not at all: every result, figure, report, table and archive goes to a
temporary name beside its final one and is renamed into place when complete, so a reader never
finds half a file under a final name; a disk that cannot take it (full, read-only, no
permission) is one line, `OutputError`, naming what was written, where, and how much space it
needed. `folder_lock` reserves an output folder for one run at a time, so two runs into one folder
never mix their files.
"""

from __future__ import annotations

import errno
import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from .errors import InputError

FULL = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)


class OutputError(InputError):
    """Results that could not be written: one line naming what, where and why (the space needed)."""


def _mode() -> int:
    """The mode a new file gets under this process's umask (a temporary file is made 0600)."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def free(folder: Path) -> int:
    """Bytes free on the disk that holds `folder` (or its nearest existing parent)."""
    existing = Path(folder)
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    return shutil.disk_usage(existing).free


def _failed(what: str, path: Path, error: OSError, needed: int | None) -> OutputError:
    where = f"{what} {path}"
    if error.errno in FULL:
        size = f"needs {needed / 1e6:.1f} MB, " if needed else ""
        return OutputError(f"{where} could not be written: {size}{free(path.parent) / 1e6:.1f} MB are free there: "
                           "the disk is full")
    if error.errno in (errno.EROFS, errno.EACCES, errno.EPERM):
        return OutputError(f"{where} could not be written: {path.parent} is not writable ({error.strerror})")
    return OutputError(f"{where} could not be written: {error.strerror or error}")


@contextmanager
def replacing(path: Path, what: str, needed: int | None = None) -> Iterator[Path]:
    """A temporary path beside `path` to write to, renamed onto `path` when the block ends and
    removed when it fails. `needed` (bytes, where known or estimated) is checked against the free
    space first. A disk that cannot take the file raises OutputError naming `what`, the path and
    the space it needed; nothing is left under either name."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if needed is not None and needed > free(path.parent):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        handle, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
        os.close(handle)
    except OSError as error:
        raise _failed(what, path, error, needed) from None
    temporary = Path(name)
    try:
        yield temporary
        os.chmod(temporary, _mode())
        os.replace(temporary, path)
    except OSError as error:
        written = temporary.stat().st_size if temporary.exists() else 0
        temporary.unlink(missing_ok=True)
        raise _failed(what, path, error, needed or written or None) from None
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


@contextmanager
def appending(path: Path, what: str) -> Iterator:
    """`path` opened to append text (a table growing row by row, rebuilt whole when it is read
    back); a disk that cannot take it raises OutputError naming `what`."""
    try:
        with open(path, "a", newline="") as file:
            yield file
    except OSError as error:
        raise _failed(what, Path(path), error, None) from None


def write_bytes(path: Path, data: bytes, what: str) -> Path:
    """`data` written whole to `path` (see `replacing`)."""
    with replacing(path, what, len(data)) as temporary:
        temporary.write_bytes(data)
    return Path(path)


def write_text(path: Path, text: str, what: str) -> Path:
    """`text` (UTF-8) written whole to `path` (see `replacing`)."""
    return write_bytes(path, text.encode("utf-8"), what)


@contextmanager
def folder_lock(folder: Path) -> Iterator[None]:
    """The output folder reserved for this process while the block runs: a lock in this user's
    cache (cosim.engine.cache) named after the folder's path, so the folder itself is not touched
    (a run that never starts leaves it as it was), freed when the process ends however it ends. A
    second run into the folder meanwhile is refused in one line rather than mixing its files with
    these."""
    import fcntl
    import zlib  # two 32-bit checksums name the lock: hashlib's OpenSSL costs a run 8 ms to load
    from .cache import cache_dir
    folder = Path(folder).resolve()
    locks = cache_dir() / "locks"
    locks.mkdir(mode=0o700, exist_ok=True)
    path = str(folder).encode()
    handle = open(locks / f"{zlib.crc32(path):08x}{zlib.adler32(path):08x}.lock", "a+")
    try:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.seek(0)
            holder = handle.read().strip() or "another process"
            raise OutputError(f"{folder} is in use by another run ({holder}): its files and this run's would mix; "
                              "give this run another output folder or wait for that one") from None
        handle.seek(0)
        handle.truncate()
        handle.write(f"pid {os.getpid()}, {folder}")
        handle.flush()
        yield
    finally:
        handle.close()


def write_figure(figure, path: Path, dpi: int, what: str = "a figure") -> Path:
    """A matplotlib figure saved whole to `path` (its format from the suffix)."""
    path = Path(path)
    with replacing(path, what) as temporary:
        figure.savefig(temporary, dpi=dpi, format=path.suffix.lstrip(".") or "png")
    return path
