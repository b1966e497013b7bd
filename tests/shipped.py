"""The shipped models, from the one list that CMake and the fuzz script read too (fmu/models.txt)."""

from __future__ import annotations

from cosim.engine.artifacts import ROOT

MODELS = tuple(line.strip() for line in (ROOT / "fmu" / "models.txt").read_text().splitlines()
               if line.strip() and not line.startswith("#"))
