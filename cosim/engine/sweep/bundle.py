"""The files a sweep's points read, sent to Dask workers by content.

A worker needs the installed package and nothing else: the target (a scene file, an SSP archive)
and every file it refers to (a user's drive FMU, a trajectory table) travel with the sweep. The
client hashes each file (SHA-256), scatters the bytes once to every worker, and each worker writes
each blob once into its cache (COSIM_CACHE_DIR, default <temp>/cosim-cache: blobs/<hash>) and lays
the files out under bundles/<key>/ as they lay relative to each other, so a scene's relative paths
hold there. The project's own FMUs and data come from the worker's installed package. A file
already cached is not written again; a worker that restarts finds it.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence


def cache_dir() -> Path:
    return Path(os.environ.get("COSIM_CACHE_DIR") or Path(tempfile.gettempdir()) / "cosim-cache")


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
            digest = hashlib.sha256(data).hexdigest()
            blobs[digest] = data
            entries.append((path.relative_to(root).as_posix(), digest))
        return cls(paths[0].relative_to(root).as_posix(), tuple(entries)), blobs

    def place(self, blobs: Mapping[str, bytes]) -> Path:
        """Writes what is not yet in this machine's cache and returns the target's path there."""
        cache = cache_dir()
        root = cache / "bundles" / self.key
        for relative, digest in self.files:
            blob = cache / "blobs" / digest
            if not blob.exists():
                _write(blob, blobs[digest])
            placed = root / relative
            if not placed.exists():
                _write(placed, blob.read_bytes())
        return root / self.main


def _write(path: Path, data: bytes) -> None:
    """Writes atomically (a rename), so two workers of one machine never read half a file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    with os.fdopen(handle, "wb") as file:
        file.write(data)
    os.replace(temporary, path)
