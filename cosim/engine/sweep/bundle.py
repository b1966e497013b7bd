"""The files a sweep's points read, sent to Dask workers by content, into a cache that trusts
nothing it finds.

A worker needs the installed package and nothing else: the target (a scene file, an SSP archive)
and every file it refers to (a user's drive FMU, a trajectory table) travel with the sweep. The
client hashes each file (SHA-256), scatters the bytes once to every worker, and each worker keeps
them in its user's cache (`cache_dir`: COSIM_CACHE_DIR, default the platform's user cache folder,
e.g. ~/.cache/cosim) as blobs/<hash> and lays them out under bundles/<key>/ as they lay relative
to each other, so a scene's relative paths hold there. The cache is private (0700) and refused
when another user owns it or others may write to it; a file found in it (a blob, or a bundle's
file) is used only when its SHA-256 is the one the sweep shipped, and replaced otherwise, so a
file planted there beforehand is never run. The project's own FMUs and data come from the worker's
installed package.
"""

from __future__ import annotations

import hashlib
import os
import stat
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

from ..cache import CacheError, cache_dir


def digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


@dataclass(frozen=True)
class Bundle:
    main: str                            # the target's path, relative to the bundle's root
    files: tuple[tuple[str, str], ...]   # (path relative to the root, SHA-256 of its bytes)

    @property
    def key(self) -> str:
        return hashlib.sha256(repr(self.files).encode()).hexdigest()[:32]

    @classmethod
    def of(cls, target: Path, files: Sequence[Path] = ()) -> tuple["Bundle", dict[str, bytes]]:
        """The bundle of `target` and the files it refers to, with their bytes by hash."""
        paths = list(dict.fromkeys(Path(p).resolve() for p in (target, *files)))
        root = Path(os.path.commonpath([p.parent for p in paths]))
        blobs: dict[str, bytes] = {}
        entries = []
        for path in paths:
            data = path.read_bytes()
            blobs[digest(data)] = data
            entries.append((path.relative_to(root).as_posix(), digest(data)))
        return cls(paths[0].relative_to(root).as_posix(), tuple(entries)), blobs

    def place(self, blobs: Mapping[str, bytes]) -> Path:
        """Lays the bundle out in this machine's cache, each file checked against its hash (a blob
        or a laid-out file that differs is replaced from the shipped bytes), and returns the
        target's path there."""
        cache = cache_dir()
        root = cache / "bundles" / self.key
        for relative, expected in self.files:
            shipped = blobs[expected]
            if digest(shipped) != expected:
                raise CacheError(f"the sweep's file {relative} arrived damaged (its SHA-256 is not the one sent)")
            blob = cache / "blobs" / expected
            if not holds(blob, expected):
                _write(blob, shipped)
            placed = root / relative
            if not holds(placed, expected):
                _write(placed, shipped)
        return root / self.main


def holds(path: Path, expected: str) -> bool:
    """Whether `path` is a plain file (not a link) whose SHA-256 is `expected`."""
    try:
        if not stat.S_ISREG(os.lstat(path).st_mode):
            return False
        return digest(path.read_bytes()) == expected
    except OSError:
        return False


def _write(path: Path, data: bytes) -> None:
    """Writes atomically (a rename over whatever stood there, a link included), so two workers of
    one machine never read half a file."""
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    with os.fdopen(handle, "wb") as file:
        file.write(data)
    os.replace(temporary, path)
