"""Imports go one way (docs/guide/layout.md): the engine knows nothing of the platform, the command
line or the API; the platform application knows nothing of the command line or the API; and
inside the platform application each room imports only from the rooms before it. Every import
of every module counts, those inside functions too."""

from __future__ import annotations

import ast
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
