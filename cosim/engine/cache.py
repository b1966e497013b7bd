"""This user's private cache folder: the files sweeps ship to their workers (cosim.engine.sweep.
bundle) and the locks that keep two runs out of one output folder (cosim.engine.files). It is
COSIM_CACHE_DIR, or the platform's user cache folder (~/.cache/cosim on Linux), created private
(0700) and refused, in one line, when it is a link, belongs to another user, or others may write
to it: nothing found in a folder someone else controls is trusted."""

from __future__ import annotations

import os
import stat
import sys
from pathlib import Path

from .errors import InputError


class CacheError(InputError):
    """A cache folder this process must not trust: one line naming it and why."""


def _user_cache() -> Path:
    """The platform's per-user cache folder for cosim."""
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / "cosim"
    if os.name == "nt":
        return Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local") / "cosim" / "Cache"
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "cosim"


def cache_dir() -> Path:
    """This user's cache of the files sweeps ship (COSIM_CACHE_DIR, or the platform's user cache
    folder), made private (0700) if it is new. Raises CacheError when it is not a folder of its
    own (a link), belongs to another user, or others may write to it."""
    path = Path(os.environ.get("COSIM_CACHE_DIR") or _user_cache())
    try:
        try:
            path.mkdir(mode=0o700, parents=True, exist_ok=True)
        except FileExistsError:  # a file there: refused below
            pass
        status = os.lstat(path)
    except OSError as error:
        raise CacheError(f"the sweep cache {path} cannot be made ({error.strerror}); set COSIM_CACHE_DIR to a private "
                         "folder") from None
    if stat.S_ISLNK(status.st_mode) or not stat.S_ISDIR(status.st_mode):
        raise CacheError(f"the sweep cache {path} is not a folder of its own (a link or a file); set COSIM_CACHE_DIR "
                         "to a private folder")
    if hasattr(os, "getuid") and status.st_uid != os.getuid():
        raise CacheError(f"the sweep cache {path} belongs to another user (uid {status.st_uid}): its files could run "
                         "as yours; set COSIM_CACHE_DIR to a folder of your own")
    if status.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        raise CacheError(f"the sweep cache {path} may be written by others (mode {stat.S_IMODE(status.st_mode):o}): "
                         f"make it private (chmod 700 {path}) or set COSIM_CACHE_DIR to a folder of your own")
    return path
