#!/usr/bin/env bash
# Sets up (scripts/setup.sh) and runs the main job: the paper's scene (Meng 2010, Eqs 35-36, PMSM
# drives) with plots like Figs 7-8, then one leg's drive on its test bench. Results go to out/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
.venv/bin/python -m cosim run scenes/meng_eq35.toml --out out "$@"
.venv/bin/python examples/drive_demo.py --out out
