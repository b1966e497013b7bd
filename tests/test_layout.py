"""Imports go one way (docs/guide/layout.md): the engine knows nothing of the platform, the command
line or the API; the platform application knows nothing of the command line or the API; and
inside the platform application each room imports only from the rooms before it. Every import
of every module counts, those inside functions too."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "cosim"
# the platform's rooms in their order: a room may import from those before it and from itself
ROOMS = {"ports": 0, "core": 1, "perception": 1, "scene": 2, "report": 3, "run": 4, "advise": 5, "design": 5,
         "realtime": 5, "validation": 6}


def imports(path: Path) -> list[str]:
    """The modules `path` imports, absolute (cosim.x.y), relative ones resolved."""
    module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    package = module.split(".")[:-1]
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            target = ".".join([*base, *([node.module] if node.module else [])])
            found += [target] if node.module else [f"{target}.{alias.name}" for alias in node.names]
    return [name for name in found if name.split(".")[0] == "cosim"]


MODULES = sorted(PACKAGE.rglob("*.py"))


@pytest.mark.parametrize("path", MODULES, ids=[str(p.relative_to(PACKAGE)) for p in MODULES])
def test_imports_go_one_way(path):
    part = path.relative_to(PACKAGE).parts
    for name in imports(path):
        target = name.split(".")[1:]
        if part[0] == "engine":
            assert target[0] == "engine", f"the engine imports {name}"
        elif part[0] == "platform":
            assert target[0] in ("engine", "platform"), f"the platform application imports {name}"
            if target[0] == "platform" and len(part) > 1 and len(target) > 1:
                room, theirs = part[1].removesuffix(".py"), target[1]
                if room in ROOMS and theirs in ROOMS and theirs != room:
                    assert ROOMS[theirs] < ROOMS[room], f"platform/{room} imports {name}, a room after it"


def test_the_rooms_are_every_part_of_the_platform():
    parts = {p.name.removesuffix(".py") for p in (PACKAGE / "platform").iterdir()
             if p.name != "__init__.py" and not p.name.startswith("__")}
    assert parts == set(ROOMS)


# ---- sizes a newcomer reads in one sitting (docs/guide/layout.md) ------------------------------

ROOT = PACKAGE.parent
C_SOURCES = sorted([*(ROOT / "fmu").rglob("*.c"), *(PACKAGE / "engine" / "kernel").rglob("*.c")])
MODULE_LINES, C_LINES, FUNCTION_LINES, FOLDER_MODULES = 600, 800, 80, 12


def lines(path: Path) -> int:
    return len(path.read_text().splitlines())


def test_every_module_is_under_600_lines():
    assert not [f"{p.relative_to(ROOT)}: {lines(p)}" for p in MODULES if lines(p) >= MODULE_LINES]


def test_every_c_source_is_under_800_lines():
    assert C_SOURCES
    assert not [f"{p.relative_to(ROOT)}: {lines(p)}" for p in C_SOURCES if lines(p) >= C_LINES]


def c_functions(path: Path) -> list[tuple[str, int]]:
    """Each function definition of a C source (its signature starts at column 0, its body ends
    with a '}' alone at column 0) and its length in lines, signature included."""
    found, start = [], None
    for number, line in enumerate(path.read_text().splitlines()):
        if start is None and re.match(r"[A-Za-z_].*\(", line) and not line.rstrip().endswith(";") \
                and not line.startswith(("typedef", "#")):
            start = number
        elif start is not None and line == "}":
            found.append((path.read_text().splitlines()[start].split("(")[0], number - start + 1))
            start = None
    return found


def test_no_function_is_over_80_lines():
    long = [f"{p.relative_to(ROOT)}: {n.name} {n.end_lineno - n.lineno + 1}" for p in MODULES
            for n in ast.walk(ast.parse(p.read_text())) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
            and n.end_lineno - n.lineno + 1 > FUNCTION_LINES]
    long += [f"{p.relative_to(ROOT)}: {name} {n}" for p in C_SOURCES for name, n in c_functions(p) if n > FUNCTION_LINES]
    assert not long


def test_the_c_function_scan_finds_what_it_measures():
    """The scan above finds the FMI entry points (a check that cannot pass by finding nothing)."""
    found = dict(c_functions(ROOT / "fmu" / "common" / "fmi2_layer.c"))
    assert {"fmi2Status fmi2DoStep", "fmi2Component fmi2Instantiate"} <= set(found)


@pytest.mark.parametrize("folder", sorted({p.parent for p in MODULES if p.parent != PACKAGE / "engine"
                                           and "engine" not in p.relative_to(PACKAGE).parts}),
                         ids=lambda p: str(p.relative_to(PACKAGE)) or ".")
def test_no_folder_of_the_application_holds_over_12_modules(folder):
    modules = [p.name for p in folder.glob("*.py") if p.name != "__init__.py"]
    assert len(modules) <= FOLDER_MODULES, modules


# ---- one run entry, one model list ----------------------------------------------------------------

APPLICATION = [p for p in MODULES if p.relative_to(PACKAGE).parts[0] != "engine"]


@pytest.mark.parametrize("path", APPLICATION, ids=[str(p.relative_to(PACKAGE)) for p in APPLICATION])
def test_the_application_runs_systems_through_the_one_entry(path):
    """Above the engine, a system runs through cosim.engine.run's Plan and run (or run_system):
    never its execution loop or the execute beneath run."""
    assert "cosim.engine.execution" not in imports(path)
    taken = {alias.name for node in ast.walk(ast.parse(path.read_text())) if isinstance(node, ast.ImportFrom)
             for alias in node.names}
    assert not taken & {"execute", "Execution"}, taken & {"execute", "Execution"}


def test_the_engine_names_no_platform_model():
    """The engine knows no model of the platform: no string in its code is a shipped model's name
    (fmu/models.txt, which CMake, the fuzz script and the tests read)."""
    models = {line.strip() for line in (ROOT / "fmu" / "models.txt").read_text().splitlines()
              if line.strip() and not line.startswith("#")}
    assert {"mechanics", "pmsm_drive"} <= models
    named = [f"{p.relative_to(ROOT)}:{n.lineno}: {n.value!r}" for p in MODULES
             if p.relative_to(PACKAGE).parts[0] == "engine"
             for n in ast.walk(ast.parse(p.read_text())) if isinstance(n, ast.Constant) and n.value in models]
    assert not named
