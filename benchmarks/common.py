"""Helpers shared by the benchmarks: the native drive bench (drive_bench.c) built on demand, and
`publish`, which writes a benchmark's results into docs/benchmarks.md and the user guide's copies of
them (docs/guide/*.md, the README), so no measured number is ever typed by hand."""

from __future__ import annotations

import os
import platform
import re
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import fmpy
from fmpy import read_model_description

from cosim.engine.artifacts import BUILD_DIR, ROOT, fmu_path

HERE = Path(__file__).resolve().parent
# A benchmark prints its results; with --write (taken off the command line here, before a
# benchmark's own options are read) it also writes them into the docs.
WRITE = "--write" in sys.argv
if WRITE:
    sys.argv.remove("--write")
BENCHMARKS_DOC = ROOT / "docs" / "benchmarks.md"
# the pages that quote benchmark blocks: the README and the user guide
QUOTING = (ROOT / "README.md", *sorted((ROOT / "docs" / "guide").glob("*.md")))


def _block(name: str) -> re.Pattern:
    return re.compile(rf"<!-- benchmark:{re.escape(name)} -->\n.*?<!-- /benchmark:{re.escape(name)} -->", re.S)


def blocks(text: str) -> dict[str, str]:
    """Every published block of a document, by benchmark name."""
    return {m.group(1): m.group(0) for m in
            re.finditer(r"<!-- benchmark:([\w-]+) -->\n.*?<!-- /benchmark:\1 -->", text, re.S)}


def machine() -> str:
    cpu = next((line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                if line.startswith("model name")), platform.processor()) if Path("/proc/cpuinfo").exists() else ""
    return f"{os.cpu_count()} cores, {cpu}".rstrip(", ")


def publish(name: str, command: str, lines: list[str], doc_path: Path = BENCHMARKS_DOC,
            quoting: tuple[Path, ...] = QUOTING, write: bool | None = None) -> None:
    """Prints a benchmark's results; with --write on the command line (or `write`), writes them (markdown lines) as block `name` of docs/benchmarks.md (appended
    the first time) and replaces the block of the same name in each page that quotes it (the
    README, the user guide): those only ever hold copies that a benchmark wrote
    (tests/platform/test_docs.py holds them equal)."""
    stamp = time.strftime("%Y-%m-%d")
    block = "\n".join([f"<!-- benchmark:{name} -->", f"`{command}` ({stamp}, {machine()}):", "", *lines,
                        f"<!-- /benchmark:{name} -->"])
    if not (WRITE if write is None else write):
        print(block)
        print(f"(not written into the docs: `{command} --write` writes block {name})", file=sys.stderr)
        return
    doc = doc_path.read_text() if doc_path.exists() else (
        "# Benchmarks\n\nEach block below is written by the command it names, in one run; the user guide quotes "
        "these blocks (its copies are rewritten by the same command). Ratios are measured within one run; "
        "lone times vary by about +-30 % between runs on this machine.\n")
    pattern = _block(name)
    doc = pattern.sub(lambda _: block, doc) if pattern.search(doc) else doc.rstrip("\n") + "\n\n" + block + "\n"
    doc_path.write_text(doc)
    quoted = []
    for page in quoting:
        text = page.read_text()
        if pattern.search(text):
            page.write_text(pattern.sub(lambda _: block, text))
            quoted.append(page.name)
    print(f"written: {doc_path.name} [{name}]" + (f" and {', '.join(quoted)}" if quoted else ""), file=sys.stderr)


def native_bench(name: str = "drive_bench") -> Path:
    """Compiles benchmarks/<name>.c (once per change) and returns the executable."""
    exe = BUILD_DIR / "bench" / name
    source = HERE / f"{name}.c"
    if not exe.exists() or exe.stat().st_mtime < source.stat().st_mtime:
        exe.parent.mkdir(parents=True, exist_ok=True)
        headers = Path(fmpy.__file__).parent / "c-code"
        subprocess.run([os.environ.get("CC", "cc"), "-O2", "-std=c99", "-Wall", "-Wextra", "-Wpedantic",
                        f"-I{headers}", str(source), "-o", str(exe), "-ldl", "-lm", "-pthread"], check=True)
    return exe


def fmu_library(fmu_name: str) -> tuple[Path, dict, str]:
    """The FMU's binary (extracted next to the build), its variables by name, and its GUID."""
    path = fmu_path(fmu_name)
    md = read_model_description(str(path))
    lib = BUILD_DIR / "stage" / fmu_name / "binaries" / "linux64" / f"{fmu_name}.so"
    if not lib.exists():
        with zipfile.ZipFile(path) as z:
            z.extractall(BUILD_DIR / "stage" / fmu_name)
    return lib, {v.name: v for v in md.modelVariables}, md.guid


def value_arguments(variables: dict, values: dict) -> list[str]:
    arguments = []
    for name, value in values.items():
        kind = {"Integer": "i", "Enumeration": "i", "Boolean": "b"}.get(variables[name].type, "r")
        arguments.append(f"{kind}{variables[name].valueReference}={int(value) if kind != 'r' else float(value)!r}")
    return arguments


def run_stepping(fmu_name: str, step: float, seconds: float, values: dict, repeats: int = 1) -> float:
    """CPU seconds per simulated second of one instance stepped from C with constant inputs (the
    least of `repeats` runs: a busy spell of the machine only ever adds)."""
    lib, variables, guid = fmu_library(fmu_name)
    args = [str(native_bench("fmu_step_bench")), str(lib), guid, repr(step), repr(seconds),
            *value_arguments(variables, values)]
    return min(float(subprocess.run(args, check=True, capture_output=True, text=True).stdout.split()[0])
               for _ in range(repeats))


def run_native(fmu_name: str, ports: tuple[str, str, str, str], step: float, seconds: float, inertia: float,
               amplitude: float, frequency: float, parameters: dict[str, float | int]) -> tuple[float, float]:
    """CPU seconds per simulated second and the final tracking error of one drive instance on a
    rigid load, stepped from C. `ports` names the reference, position, velocity and effort ports."""
    lib, variables, guid = fmu_library(fmu_name)
    args = [str(native_bench()), str(lib), guid, repr(step), repr(seconds), repr(inertia), repr(amplitude),
            repr(frequency), *[str(variables[p].valueReference) for p in ports], *value_arguments(variables, parameters)]
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout.split()
    return float(out[0]), float(out[1])
