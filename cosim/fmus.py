"""Where the built FMUs are, and building them when they are missing or older than their sources."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BUILD_DIR = ROOT / "build"
FMU_DIR = BUILD_DIR / "fmus"


TEST_FMU_DIR = BUILD_DIR / "test_fmus"
# Touched after every successful build: the build is current when it is newer than every source
# (an output CMake did not need to rewrite keeps its old time, so outputs' times cannot tell).
BUILD_STAMP = BUILD_DIR / "built.stamp"


def _newest_source_time() -> float:
    paths = [ROOT / "CMakeLists.txt", *(ROOT / "cmake").glob("*"), *(ROOT / "fmu").rglob("*"),
             *(ROOT / "tests" / "fmus").rglob("*"), *(ROOT / "cosim" / "native").rglob("*.c")]
    return max(p.stat().st_mtime for p in paths if p.is_file())


def _cmake() -> str:
    local = Path(sys.executable).parent / "cmake"
    return str(local) if local.exists() else (shutil.which("cmake") or "cmake")


def build_fmus() -> None:
    """Configures (once) and builds every FMU with CMake; raises with the build log on failure."""
    cmake = _cmake()
    steps = []
    if not (BUILD_DIR / "CMakeCache.txt").exists():
        steps.append([cmake, "-S", str(ROOT), "-B", str(BUILD_DIR), f"-DPython3_EXECUTABLE={sys.executable}"])
    steps.append([cmake, "--build", str(BUILD_DIR), "-j", str(os.cpu_count() or 2)])
    for command in steps:
        result = subprocess.run(command, capture_output=True, text=True)
        if result.returncode != 0:
            raise RuntimeError(f"FMU build failed: {' '.join(command)}\n{result.stdout}\n{result.stderr}")
    BUILD_STAMP.touch()


def _build_if_stale(path: Path) -> None:
    if not path.exists() or not BUILD_STAMP.exists() or BUILD_STAMP.stat().st_mtime < _newest_source_time():
        build_fmus()


def fmu_path(name: str, rebuild_if_stale: bool = True, test: bool = False) -> Path:
    """Path of build/fmus/<name>.fmu (build/test_fmus/ for a test FMU), built first if it is missing
    or older than the C sources."""
    path = (TEST_FMU_DIR if test else FMU_DIR) / f"{name}.fmu"
    if rebuild_if_stale:
        _build_if_stale(path)
    if not path.exists():
        raise FileNotFoundError(f"no FMU '{name}': {path} was not built (is there a fmu/{name}/ folder?)")
    return path


def native_library_path(name: str = "libcosim_loop.so", rebuild_if_stale: bool = True) -> Path:
    """Path of a native library of build/lib/ (the master's inner loop cosim/native/loop.c, the
    mechanics' dynamics core libplatform_core.so), built like the FMUs."""
    path = BUILD_DIR / "lib" / name
    if rebuild_if_stale:
        _build_if_stale(path)
    if not path.exists():
        raise FileNotFoundError(f"{path} was not built")
    return path
