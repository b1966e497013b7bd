"""Where the built artifacts and the shipped data are, in either of the package's two layouts:

- installed from a wheel (`pip install stewart-cosim`, or `pip install <checkout>`, which builds
  one with scikit-build-core): everything inside the package, `cosim/_data/`: fmus/ (the FMUs),
  fmus3/ (the same as FMI 3.0), fmus_me/ and fmus3_me/ (Model Exchange), lib/ (the engine's step kernel, the mechanics' dynamics core), params/, scenes/, sweeps/;
- a checkout (`bash scripts/setup.sh`: CMake into build/, the Python package installed editable
  without it): build/fmus/, build/fmus3/, build/fmus_me/, build/fmus3_me/, build/test_fmus/, build/lib/ and the checkout's params/, scenes/,
  sweeps/. COSIM_BUILD_DIR points at another build folder.

The package never builds anything at run time. A missing artifact, or a checkout's build older
than the C sources it comes from, is an `ArtifactMissing` error with one line that says which
command builds it.
"""

from __future__ import annotations

import functools
import os
from pathlib import Path

PACKAGE_DATA = Path(__file__).resolve().parents[1] / "_data"  # a wheel's artifacts and data
INSTALLED = PACKAGE_DATA.is_dir() and "COSIM_BUILD_DIR" not in os.environ
# the checkout, or in an installed package the folder of its data (params/, scenes/, sweeps/)
ROOT = PACKAGE_DATA if INSTALLED else Path(__file__).resolve().parents[2]
BUILD_DIR = PACKAGE_DATA if INSTALLED else Path(os.environ.get("COSIM_BUILD_DIR", ROOT / "build"))
FMU_DIR = BUILD_DIR / "fmus"
FMU3_DIR = BUILD_DIR / "fmus3"  # the same models as FMI 3.0 Co-Simulation FMUs
FMU_ME_DIR = BUILD_DIR / "fmus_me"  # the models that offer it as FMI 2.0 Model Exchange FMUs
FMU3_ME_DIR = BUILD_DIR / "fmus3_me"  # and as FMI 3.0 Model Exchange FMUs
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
    if INSTALLED or not (ROOT / "CMakeLists.txt").exists():
        return []
    return [ROOT / "CMakeLists.txt", *(ROOT / "cmake").glob("*"), *(ROOT / "fmu").rglob("*"),
            *(ROOT / "tests" / "fmus").rglob("*"), *(ROOT / "cosim" / "engine" / "kernel").rglob("*.[ch]")]


@functools.lru_cache(maxsize=1)
def _newest_source() -> tuple[float, Path] | None:
    """The newest C source or build file and its time, looked up once a process (a run asks for
    its FMUs and libraries dozens of times; the sources do not change under it)."""
    sources = [p for p in _sources() if p.is_file()]
    if not sources:
        return None
    newest = max(sources, key=lambda p: p.stat().st_mtime)
    return newest.stat().st_mtime, newest


def _check(path: Path, what: str) -> Path:
    if not path.exists():
        if not INSTALLED and not (ROOT / "CMakeLists.txt").exists():  # neither a wheel nor a checkout
            data_dir("params")
        raise ArtifactMissing(f"{what} is not built ({path} is missing): run `{BUILD_COMMAND}`")
    newest = _newest_source()
    if newest and (not BUILD_STAMP.exists() or BUILD_STAMP.stat().st_mtime < newest[0]):
        raise ArtifactMissing(f"the build in {BUILD_DIR} is older than {newest[1].relative_to(ROOT)}: "
                              f"run `{BUILD_COMMAND}`")
    return path


def data_dir(name: str) -> Path:
    """A folder of the shipped data (params/, scenes/, sweeps/): the wheel's or the checkout's. A
    copy of the Python files alone (installed without the wheel's build) has none of it, nor the
    FMUs and libraries: one line says so."""
    path = ROOT / name
    if not path.is_dir():
        raise ArtifactMissing(f"this cosim ({Path(__file__).parents[1]}) has neither its wheel's data nor a checkout, "
                              f"which hold {name}/, the FMUs and the native libraries: install the wheel "
                              f"(`pip install <checkout>` builds one) or run `{BUILD_COMMAND}` in a checkout")
    return path


def fmu_path(name: str, test: bool = False, fmi: int = 2, model_exchange: bool = False) -> Path:
    """Path of build/fmus/<name>.fmu (build/test_fmus/ for a test-only FMU; build/fmus3/ for the
    FMI 3.0 one, fmi=3; build/fmus_me/ and build/fmus3_me/ for the Model Exchange ones)."""
    if fmi == 3:
        if model_exchange:
            return _check(FMU3_ME_DIR / f"{name}.fmu", f"FMI 3.0 Model Exchange FMU '{name}'")
        return _check(FMU3_DIR / f"{name}.fmu", f"FMI 3.0 FMU '{name}'")
    if model_exchange:
        return _check(FMU_ME_DIR / f"{name}.fmu", f"Model Exchange FMU '{name}'")
    return _check((TEST_FMU_DIR if test else FMU_DIR) / f"{name}.fmu", f"FMU '{name}'")


def built_here(fmu: Path) -> bool:
    """Whether `fmu` is one of this project's built FMUs (build/fmus*/): one that takes the values
    it carries (cosim.engine.carry), as a user's FMU need not."""
    return Path(fmu).resolve().parent in {d.resolve() for d in (FMU_DIR, FMU3_DIR, FMU_ME_DIR, FMU3_ME_DIR)}


def library_path(name: str) -> Path:
    """Path of a native library of build/lib/ (libcosim_kernel.so, libplatform_core.so)."""
    return _check(LIB_DIR / name, f"library '{name}'")
