"""Every FMU's Windows binary (binaries/win64/ of the FMI 2.0 FMU, binaries/x86_64-windows/ of the
FMI 3.0 one; MinGW-w64 from the same sources) as a Windows tool would run it: it imports only
Windows' own DLLs, exports the FMI functions, and under Wine runs the same experiment as its Linux
twin with the same outputs, its state kept, serialized and set
back included, and a call in the wrong state refused (tests/c/fmu_run.c drives both binaries).

The tolerance: bit for bit where the model's arithmetic is the C operators (one compiler, gcc 12,
one source, one set of flags); where it calls libm's transcendental functions (sin, exp, atan2 in
the mechanics and the drives) glibc's and the MinGW runtime's may differ in the last bit, which a
stable model carries at round-off: 1e-12 of each output's range over the run, 1e-12 absolute for
an output that stays at zero.

And by an importer we did not write: fmpy's remoting (simulate_fmu(..., remote_platform="win64"): its
Linux client drives the DLL in a Windows server under Wine over TCP) runs each FMI 2.0 DLL through
the same experiment as fmpy runs the Linux binary, to the same tolerance. It runs as an unprivileged
user: as root, fmpy 0.3.32's client hangs (docs/guide/fmus.md: its lock file is created with mode
0000, which only root can open again, so the server under Wine takes the client for gone and exits
while the client waits for it)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from conftest import FMU_EXPERIMENT_STEPS, FMU_EXPERIMENTS
from cosim.engine.artifacts import ROOT, fmu_path
from shipped import MODELS
from cosim.engine.checks import variables

WINE = shutil.which("wine64") or next((str(p) for p in (Path("/usr/lib/wine/wine64"),) if p.exists()), None)
MINGW = shutil.which("x86_64-w64-mingw32-gcc")
OBJDUMP = shutil.which("x86_64-w64-mingw32-objdump")
pytestmark = pytest.mark.skipif(not (WINE and MINGW and OBJDUMP), reason="needs Wine and MinGW-w64 (scripts/setup.sh "
                                "installs wine64 and gcc-mingw-w64-x86-64)")

STEP, STEPS = 1e-3, 2000
STEP_OF = FMU_EXPERIMENT_STEPS
EXPERIMENTS = FMU_EXPERIMENTS
WINDOWS_DLLS = {"KERNEL32.dll", "msvcrt.dll"}


@pytest.fixture(scope="module")
def harness(tmp_path_factory) -> dict[tuple[str, int], Path]:
    """tests/c/fmu_run.c built for this system (gcc) and for Windows (MinGW-w64), for FMI 2.0 and 3.0."""
    import fmpy
    folder = tmp_path_factory.mktemp("harness")
    headers = Path(fmpy.__file__).parent / "c-code"
    source = ROOT / "tests" / "c" / "fmu_run.c"
    flags = ["-O2", "-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{headers}"]
    out = {}
    for fmi, define in ((2, []), (3, ["-DFMU_RUN_FMI3"])):
        out["linux64", fmi] = folder / f"fmu_run{fmi}"
        out["win64", fmi] = folder / f"fmu_run{fmi}.exe"
        subprocess.run([os.environ.get("CC", "cc"), *flags, *define, str(source), "-o", str(out["linux64", fmi]),
                        "-ldl"], check=True)
        subprocess.run([MINGW, *flags, *define, "-D__USE_MINGW_ANSI_STDIO=1", str(source), "-o",
                        str(out["win64", fmi]), "-static-libgcc"], check=True)
    return out


@pytest.fixture(scope="module")
def wine_env(tmp_path_factory) -> dict[str, str]:
    """A Wine prefix of the tests' own, started once (its first start builds it)."""
    env = {**os.environ, "WINEPREFIX": str(tmp_path_factory.mktemp("wine")), "WINEDEBUG": "-all",
           "PATH": f"{Path(WINE).parent}{os.pathsep}{os.environ.get('PATH', '')}"}
    subprocess.run([WINE, "wineboot", "--init"], env=env, check=False, capture_output=True, timeout=300)
    return env


def unpack(name: str, folder: Path, fmi: int = 2) -> tuple[Path, str]:
    with zipfile.ZipFile(fmu_path(name, fmi=fmi)) as archive:
        archive.extractall(folder)
    import re
    token = re.search(r'(?:guid|instantiationToken)="([^"]+)"', (folder / "modelDescription.xml").read_text()).group(1)
    return folder, token


BINARIES = {2: ("linux64", "win64"), 3: ("x86_64-linux", "x86_64-windows")}  # each version's platform folders


def arguments(name: str) -> tuple[str, list[str]]:
    """The harness' VRS (every Real output) and its settings for the model's experiment."""
    found = variables(fmu_path(name))
    outputs = ",".join(str(v.valueReference) for v in found.values() if v.causality == "output" and v.type == "Real")
    kinds = {"Real": "r", "Integer": "i", "Boolean": "b", "String": "s", "Enumeration": "i"}
    settings = [f"{kinds[found[k].type]}{found[k].valueReference}={v}" for k, v in EXPERIMENTS[name].items()]
    return outputs, settings


def run(command: list[str], env: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    done = subprocess.run(command, capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stderr
    lines = [line.strip() for line in done.stdout.splitlines() if line.strip()]
    cut = lines.index("replay")
    first, again = ([[float(x) for x in line.split(",")] for line in part] for part in (lines[:cut], lines[cut + 1:]))
    return np.array(first), np.array(again)


@pytest.mark.parametrize("name", MODELS)
def test_the_windows_binary_needs_only_windows_own_dlls(name, tmp_path):
    folder, _ = unpack(name, tmp_path)
    dll = folder / "binaries" / "win64" / f"{name}.dll"
    table = subprocess.run([OBJDUMP, "-p", str(dll)], capture_output=True, text=True, check=True).stdout
    imported = {line.split(":", 1)[1].strip() for line in table.splitlines() if "DLL Name:" in line}
    assert imported == WINDOWS_DLLS
    for function in ("fmi2Instantiate", "fmi2DoStep", "fmi2GetReal", "fmi2SerializeFMUstate",
                     "fmi2GetRealOutputDerivatives", "fmi2FreeInstance"):
        assert f"] {function}\n" in table, function


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("name", MODELS)
def test_under_wine_the_windows_binary_gives_the_linux_outputs(name, fmi, tmp_path, harness, wine_env):
    folder, token = unpack(name, tmp_path, fmi)
    outputs, settings = arguments(name)
    common = [token, repr(STEP_OF.get(name, STEP)), f"{STEPS}r", outputs, *settings]
    on_linux, on_windows = (folder / "binaries" / f for f in BINARIES[fmi])
    linux, linux_again = run([str(harness["linux64", fmi]), str(on_linux / f"{name}.so"), *common])
    windows, windows_again = run([WINE, str(harness["win64", fmi]), str(on_windows / f"{name}.dll"), *common],
                                 wine_env)
    assert linux.shape == windows.shape == (STEPS + 1, 1 + len(outputs.split(",")))
    scale = np.ptp(linux, axis=0)
    assert np.all(np.abs(windows - linux) <= 1e-12 * np.maximum(scale, 1.0))
    assert np.ptp(linux[:, 1:], axis=0).max() > 0  # the experiment moves something
    # the state kept at the half, through its bytes, set back: the second half again, bit for bit
    assert np.array_equal(linux_again, linux[STEPS // 2:]) and np.array_equal(windows_again, windows[STEPS // 2:])


REMOTE_STEPS = {"cueing": 600}  # past the drive's braking at 2 s; the others 300 steps
REMOTE_RUN = """
import json, shutil, sys
import numpy as np
from fmpy import extract, simulate_fmu
fmu, start, step, folder, steps = sys.argv[1], json.loads(sys.argv[2]), float(sys.argv[3]), sys.argv[4], int(sys.argv[5])
linux_dir, windows_dir = (str(extract(fmu, folder + "/" + part)) for part in ("linux", "windows"))
shutil.rmtree(windows_dir + "/binaries/linux64")  # (fmpy remotes only an FMU without a binary for this platform)
run = dict(start_values=start, stop_time=steps * step, step_size=step, output_interval=step)
linux = simulate_fmu(linux_dir, **run)
windows = simulate_fmu(windows_dir, remote_platform="win64", **run)
np.savez(folder + "/runs.npz", linux=linux, windows=windows)
"""


def unprivileged(folder: Path) -> list[str]:
    """The command prefix that runs as an unprivileged user (nobody, where this is root) with its
    own home and Wine prefix in `folder`; skips where that user cannot reach this checkout."""
    if os.geteuid() != 0:
        return []
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        pytest.skip("setpriv (util-linux) is missing: cannot run as an unprivileged user")
    os.chown(folder, 65534, 65534)
    prefix = [setpriv, "--reuid=65534", "--regid=65534", "--clear-groups"]
    if subprocess.run([*prefix, sys.executable, "-c", "import fmpy, numpy"], capture_output=True).returncode != 0:
        pytest.skip(f"an unprivileged user cannot run {sys.executable} (this checkout is not readable by others)")
    return prefix


REMOTING_PORT = 8080  # fmpy 0.3.32's client and server meet at rpclib's default port, whatever runs


def port_taken(port: int = REMOTING_PORT) -> bool:
    import socket
    with socket.socket() as probe:
        return probe.connect_ex(("127.0.0.1", port)) == 0


@pytest.fixture(scope="module")
def remote_wine():
    """The unprivileged user's Wine, made once: a home and a Wine prefix it owns, its first start
    (which builds the prefix) done before any run. fmpy's client gives its server 20 tries half a
    second apart (remoting/client_tcp.cpp), which a prefix built in the run can outlast on a loaded
    machine; the server it started then comes up late and keeps the port from every later run."""
    import tempfile
    if WINE is None:
        pytest.skip("needs Wine (scripts/setup.sh installs wine64)")
    home = Path(tempfile.mkdtemp(prefix="cosim-wine-"))
    home.chmod(0o755)
    prefix = unprivileged(home)
    env = {**os.environ, "HOME": str(home), "WINEPREFIX": str(home / "wine"), "WINEDEBUG": "-all",
           "PATH": f"{Path(WINE).parent}{os.pathsep}{os.environ.get('PATH', '')}"}
    subprocess.run([*prefix, WINE, "wineboot", "--init"], env=env, cwd=home, timeout=600,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wineserver = [*prefix, shutil.which("wineserver", path=env["PATH"]) or "wineserver"]
    subprocess.run([*wineserver, "-w"], env=env, timeout=600)  # wait for the first start to finish
    yield {"prefix": prefix, "env": env, "wineserver": wineserver}
    subprocess.run([*wineserver, "-k"], env=env, timeout=60)
    shutil.rmtree(home, ignore_errors=True)


def run_remotely(wine: dict, folder: Path, arguments: list[str], timeout: float) -> tuple[int, str]:
    """`python arguments...` as the unprivileged user in `folder` with its prepared Wine; its
    return code and output. Every Wine process it leaves (a server that came up after its client
    gave up) is ended after it, so that the port is free for the next run."""
    assert not port_taken(), f"port {REMOTING_PORT}, where fmpy's remoting meets its server, is taken"
    os.chown(folder, *(os.stat(wine["env"]["HOME"])[4:6]))
    env = {**wine["env"], "TMPDIR": str(folder)}
    log = folder / "run.log"
    try:
        with open(log, "w") as out:  # (a file, not a pipe: a Wine process left holding it cannot stall the test)
            done = subprocess.run([*wine["prefix"], sys.executable, *arguments], stdout=out, stderr=subprocess.STDOUT,
                                  env=env, cwd=folder, timeout=timeout)  # (fmpy returns to its start folder,
        return done.returncode, log.read_text()[-4000:]                  # which must be the user's)
    finally:
        subprocess.run([*wine["wineserver"], "-k"], env=env, timeout=60)
        subprocess.run([*wine["wineserver"], "-w"], env=env, timeout=60)


@pytest.fixture
def remote_folder():
    """A folder the unprivileged user can reach (pytest's own are the user's alone), removed after."""
    import tempfile
    folder = Path(tempfile.mkdtemp(prefix="cosim-remoting-"))
    folder.chmod(0o755)
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


@pytest.mark.parametrize("name", MODELS)
def test_fmpys_remoting_runs_the_windows_binary_as_its_linux_twin(name, remote_folder, remote_wine):
    import json
    folder = remote_folder
    fmu = folder / f"{name}.fmu"
    shutil.copy(fmu_path(name), fmu)
    fmu.chmod(0o644)
    (folder / "run.py").write_text(REMOTE_RUN)
    status, output = run_remotely(remote_wine, folder, [str(folder / "run.py"), str(fmu), json.dumps(EXPERIMENTS[name]),
                                  repr(STEP_OF.get(name, STEP)), str(folder), str(REMOTE_STEPS.get(name, 300))], 600)
    assert status == 0, output
    runs = np.load(folder / "runs.npz")
    linux, windows = runs["linux"], runs["windows"]
    assert len(linux) == len(windows) == REMOTE_STEPS.get(name, 300) + 1
    moved = False
    for column in linux.dtype.names:
        scale = max(float(np.ptp(linux[column])), 1.0)
        assert np.all(np.abs(windows[column] - linux[column]) <= 1e-12 * scale), column
        moved = moved or (column != "time" and np.ptp(linux[column]) > 0)
    assert moved  # the experiment moves something
