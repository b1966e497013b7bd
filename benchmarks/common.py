"""Helpers shared by the benchmarks: the native drive bench (drive_bench.c) built on demand."""

from __future__ import annotations

import os
import subprocess
import zipfile
from pathlib import Path

import fmpy
from fmpy import read_model_description

from cosim.fmus import BUILD_DIR, fmu_path

HERE = Path(__file__).resolve().parent


def native_bench() -> Path:
    """Compiles benchmarks/drive_bench.c (once per change) and returns the executable."""
    exe = BUILD_DIR / "bench" / "drive_bench"
    source = HERE / "drive_bench.c"
    if not exe.exists() or exe.stat().st_mtime < source.stat().st_mtime:
        exe.parent.mkdir(parents=True, exist_ok=True)
        headers = Path(fmpy.__file__).parent / "c-code"
        subprocess.run([os.environ.get("CC", "cc"), "-O2", "-std=c99", "-Wall", "-Wextra", "-Wpedantic",
                        f"-I{headers}", str(source), "-o", str(exe), "-ldl", "-lm"], check=True)
    return exe


def run_native(fmu_name: str, ports: tuple[str, str, str, str], step: float, seconds: float, inertia: float,
               amplitude: float, frequency: float, parameters: dict[str, float | int]) -> tuple[float, float]:
    """CPU seconds per simulated second and the final tracking error of one drive instance on a
    rigid load, stepped from C. `ports` names the reference, position, velocity and effort ports."""
    path = fmu_path(fmu_name)
    md = read_model_description(str(path))
    variables = {v.name: v for v in md.modelVariables}
    lib = BUILD_DIR / "stage" / fmu_name / "binaries" / "linux64" / f"{fmu_name}.so"
    if not lib.exists():
        with zipfile.ZipFile(path) as z:
            z.extractall(BUILD_DIR / "stage" / fmu_name)
    args = [str(native_bench()), str(lib), md.guid, repr(step), repr(seconds), repr(inertia), repr(amplitude),
            repr(frequency), *[str(variables[p].valueReference) for p in ports]]
    for name, value in parameters.items():
        kind = "i" if variables[name].type in ("Integer", "Enumeration", "Boolean") else "r"
        args.append(f"{kind}{variables[name].valueReference}={value}")
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout.split()
    return float(out[0]), float(out[1])
