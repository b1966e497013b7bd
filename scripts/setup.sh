#!/usr/bin/env bash
# Sets up a fresh machine for this project: a virtual environment with the pinned Python
# dependencies (fmpy also provides the FMI 2.0 headers), then builds every FMU into build/fmus/.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  "$PYTHON" -m venv .venv
fi
.venv/bin/python -m pip install --quiet --upgrade pip
.venv/bin/python -m pip install --quiet -r requirements.txt
.venv/bin/python -m pip install --quiet --no-deps -e .
.venv/bin/cmake -S . -B build -DPython3_EXECUTABLE="$PWD/.venv/bin/python" > build.log 2>&1 || { cat build.log; exit 1; }
.venv/bin/cmake --build build -j 2 >> build.log 2>&1 || { cat build.log; exit 1; }
touch build/built.stamp  # cosim.engine.artifacts: the build is current
echo "FMUs built:" build/fmus/*.fmu
