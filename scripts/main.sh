#!/usr/bin/env bash
# Sets up (scripts/setup.sh) and runs the main job; results and plots go to out/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
.venv/bin/python -m cosim.drive_demo --out out "$@"
