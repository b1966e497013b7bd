"""Where the built artifacts are: the FMUs (build/fmus/), the test FMUs (build/test_fmus/) and the
native libraries (build/lib/: the engine's step kernel, the mechanics' dynamics core).

The package never builds anything: `bash scripts/setup.sh` does (CMake). A missing artifact, or a
build older than the C sources it comes from, is an `ArtifactMissing` error with one line that
says which command builds it. COSIM_BUILD_DIR points at another build folder.
"""

from __future__ import annotations

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BUILD_DIR = Path(os.environ.get("COSIM_BUILD_DIR", ROOT / "build"))
FMU_DIR = BUILD_DIR / "fmus"
TEST_FMU_DIR = BUILD_DIR / "test_fmus"
LIB_DIR = BUILD_DIR / "lib"
# Touched by scripts/setup.sh after every successful build: the build is current when it is newer
# than every C source (an output CMake did not need to rewrite keeps its old time).
BUILD_STAMP = BUILD_DIR / "built.stamp"
BUILD_COMMAND = "bash scripts/setup.sh"


class ArtifactMissing(FileNotFoundError):
    """A built FMU or library is missing or older than its sources; the message says how to build."""


def _sources() -> list[Path]:
    """The C sources and build files of this checkout (none in an installed package)."""
    if not (ROOT / "CMakeLists.txt").exists():
        return []
    return [ROOT / "CMakeLists.txt", *(ROOT / "cmake").glob("*"), *(ROOT / "fmu").rglob("*"),
            *(ROOT / "tests" / "fmus").rglob("*"), *(ROOT / "cosim" / "engine" / "kernel").rglob("*.[ch]")]


def _check(path: Path, what: str) -> Path:
    if not path.exists():
        raise ArtifactMissing(f"{what} is not built ({path} is missing): run `{BUILD_COMMAND}`")
    sources = [p for p in _sources() if p.is_file()]
    if sources and (not BUILD_STAMP.exists() or BUILD_STAMP.stat().st_mtime < max(p.stat().st_mtime for p in sources)):
        newest = max(sources, key=lambda p: p.stat().st_mtime)
        raise ArtifactMissing(f"the build in {BUILD_DIR} is older than {newest.relative_to(ROOT)}: "
                              f"run `{BUILD_COMMAND}`")
    return path


def data_dir(name: str) -> Path:
    """A folder of the checkout's data (params/, scenes/). A copy installed without the checkout
    (`pip install <checkout>`) has none of it, nor the FMUs and libraries: one line says so."""
    path = ROOT / name
    if not path.is_dir():
        raise ArtifactMissing(f"this cosim ({Path(__file__).parents[1]}) is installed without its checkout, "
                              f"which holds {name}/, the FMUs and the native libraries: install it from the "
                              f"checkout with `{BUILD_COMMAND}` (an editable install) and run that one")
    return path


def fmu_path(name: str, test: bool = False) -> Path:
    """Path of build/fmus/<name>.fmu (build/test_fmus/ for a test-only FMU)."""
    return _check((TEST_FMU_DIR if test else FMU_DIR) / f"{name}.fmu", f"FMU '{name}'")


def library_path(name: str) -> Path:
    """Path of a native library of build/lib/ (libcosim_kernel.so, libplatform_core.so)."""
    return _check(LIB_DIR / name, f"library '{name}'")
