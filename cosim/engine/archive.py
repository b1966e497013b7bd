"""An SSP archive unpacked safely (cosim.engine.ssp reads what it holds): within limits on its size
in all, its entries and each entry's packing ratio, checked from its directory before anything is
written and again byte by byte while it unpacks; no entry climbs out of the folder or is a link;
a full disk named as one."""

from __future__ import annotations

import errno
import os
import shutil
import stat
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path

from .errors import SspError


@dataclass(frozen=True)
class ArchiveLimits:
    """What an SSP archive may unpack to, checked from its directory before anything is written and
    again, byte by byte, while it unpacks: the bytes in all, the entries, and an entry's unpacked
    size against its packed size (a zip bomb's ratio is in the thousands; FMUs and SSVs pack by
    2-20). Set by COSIM_SSP_MAX_BYTES, COSIM_SSP_MAX_ENTRIES and COSIM_SSP_MAX_RATIO."""
    total_bytes: int = 1 << 30   # 1 GiB
    entries: int = 10_000
    ratio: float = 200.0         # for entries larger than RATIO_FROM bytes unpacked
    RATIO_FROM = 1 << 20

    @classmethod
    def from_environment(cls) -> "ArchiveLimits":
        given = {}
        for name, field_name, kind in (("COSIM_SSP_MAX_BYTES", "total_bytes", int),
                                       ("COSIM_SSP_MAX_ENTRIES", "entries", int),
                                       ("COSIM_SSP_MAX_RATIO", "ratio", float)):
            if os.environ.get(name):
                try:
                    given[field_name] = kind(float(os.environ[name]))
                except ValueError:
                    raise SspError(f"{name}={os.environ[name]!r}: must be a number") from None
        return cls(**given)


def unpack(path: Path, folder: Path, limits: ArchiveLimits | None = None) -> None:
    """Unpacks the archive into `folder` within the limits; an entry whose name climbs out of the
    folder (an absolute name, '..') or is a link is refused, naming it; a full disk is named as one.
    Raises SspError (one line)."""
    limits = limits or ArchiveLimits.from_environment()
    try:
        with zipfile.ZipFile(path) as archive:
            entries = archive.infolist()
            _check_directory(path, entries, limits)
            needed = sum(e.file_size for e in entries)
            free = shutil.disk_usage(folder).free
            if needed > free:
                raise SspError(f"{path}: unpacking needs {needed / 1e6:.1f} MB in {folder}, only {free / 1e6:.1f} MB "
                               "are free: the disk is full")
            written = 0
            for entry in entries:
                written += _unpack_entry(path, archive, entry, folder, limits.total_bytes - written)
    except SspError:
        raise
    except zipfile.BadZipFile:
        raise SspError(f"{path}: not an SSP archive (not a zip file)") from None
    except OSError as error:
        if error.errno in (errno.ENOSPC, errno.EDQUOT):
            raise SspError(f"{path}: the disk is full: no space left in {folder} to unpack the archive") from None
        raise SspError(f"{path}: a damaged SSP archive, its files cannot be unpacked ({error})") from None
    except (EOFError, ValueError, zlib.error, NotImplementedError) as error:  # damaged, or a method zipfile lacks
        raise SspError(f"{path}: a damaged SSP archive, its files cannot be unpacked ({error})") from None


def _check_directory(path: Path, entries: list[zipfile.ZipInfo], limits: ArchiveLimits) -> None:
    """The archive's directory against the limits, before anything is written."""
    if len(entries) > limits.entries:
        raise SspError(f"{path}: {len(entries)} entries; an SSP archive may hold {limits.entries} "
                       "(COSIM_SSP_MAX_ENTRIES)")
    for entry in entries:
        parts = entry.filename.replace("\\", "/").split("/")
        if entry.filename.startswith(("/", "\\")) or ":" in parts[0] or ".." in parts:
            raise SspError(f"{path}: entry {entry.filename!r} climbs out of the archive's folder (an absolute name "
                           "or '..'): refused")
        if stat.S_ISLNK(entry.external_attr >> 16):
            raise SspError(f"{path}: entry {entry.filename!r} is a link: refused")
        if entry.file_size > limits.RATIO_FROM and entry.file_size > limits.ratio * max(entry.compress_size, 1):
            raise SspError(f"{path}: entry {entry.filename!r} unpacks to {entry.file_size / 1e6:.1f} MB, "
                           f"{entry.file_size / max(entry.compress_size, 1):.0f} times its packed size; at most "
                           f"{limits.ratio:g} times (COSIM_SSP_MAX_RATIO)")
    total = sum(e.file_size for e in entries)
    if total > limits.total_bytes:
        raise SspError(f"{path}: unpacks to {total / 1e6:.1f} MB; an SSP archive may unpack to "
                       f"{limits.total_bytes / 1e6:.1f} MB (COSIM_SSP_MAX_BYTES)")


def _unpack_entry(path: Path, archive: zipfile.ZipFile, entry: zipfile.ZipInfo, folder: Path, allowed: int) -> int:
    """One entry streamed out with a running count (its declared size is not trusted); returns the
    bytes written."""
    target = folder / entry.filename
    if entry.is_dir():
        target.mkdir(parents=True, exist_ok=True)
        return 0
    target.parent.mkdir(parents=True, exist_ok=True)
    written = 0
    with archive.open(entry) as source, open(target, "wb") as out:
        while chunk := source.read(1 << 20):
            written += len(chunk)
            if written > entry.file_size or written > allowed:
                raise SspError(f"{path}: entry {entry.filename!r} unpacks to more than its directory says "
                               f"({entry.file_size} bytes) or than the archive may: refused")
            out.write(chunk)
    return written
