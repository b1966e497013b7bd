#!/usr/bin/env bash
# Sets up a fresh machine for this project: a virtual environment with the pinned Python
# dependencies (fmpy also provides the FMI 2.0 headers), then builds every FMU into build/fmus/.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3}
# Ecos (ecospy, one of the tools the SSP tests run the exported system in) links against Intel
# TBB: Debian's libtbb12; the TLS sweep test makes its certificates with openssl; every FMU's
# binaries/win64/ is cross-compiled by MinGW-w64 and tested under Wine (wine64 lives in
# /usr/lib/wine, off the PATH).
missing=""
ldconfig -p 2>/dev/null | grep -q "libtbb.so.12" || missing="$missing libtbb12"
# the peers' fmusim (Reference-FMUs, the tests' third-party importer) links against libxml2 and minizip
ldconfig -p 2>/dev/null | grep -q "libminizip.so.1" || missing="$missing libminizip1"
ldconfig -p 2>/dev/null | grep -q "libxml2.so.2" || missing="$missing libxml2"
command -v openssl > /dev/null 2>&1 || missing="$missing openssl"
command -v x86_64-w64-mingw32-gcc > /dev/null 2>&1 || missing="$missing gcc-mingw-w64-x86-64"
{ command -v wine64 > /dev/null 2>&1 || [ -x /usr/lib/wine/wine64 ]; } || missing="$missing wine64"
if [ -z "$missing" ]; then
  echo "setup: the system packages are present (TBB, minizip, libxml2, openssl, MinGW-w64, Wine)"
else
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  # shellcheck disable=SC2086
  $SUDO apt-get update -qq > apt.log 2>&1 && $SUDO apt-get install -y -qq $missing >> apt.log 2>&1 \
    || { cat apt.log; echo "could not install$missing (needed by ecospy, the win64 binaries, fmusim and the tests)" >&2; exit 1; }
fi
# Each step once: the environment is made again only when what it is made from changed (the pinned
# requirements, pyproject.toml, the Python), and CMake builds only what changed.
wanted="$(cat requirements.txt pyproject.toml | sha256sum | cut -c1-16) $("$PYTHON" --version 2>&1)"
stamp=.venv/.cosim-environment
if [ -x .venv/bin/python ] && [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$wanted" ]; then
  echo "setup: .venv/ is current (requirements.txt, pyproject.toml and $("$PYTHON" --version 2>&1) as when it was made)"
else
  if [ ! -x .venv/bin/python ]; then
    "$PYTHON" -m venv .venv
  fi
  .venv/bin/python -m pip install --quiet --upgrade pip
  .venv/bin/python -m pip install --quiet -r requirements.txt
  # the package editable, its Python files from this checkout; CMake builds the C parts into build/ below
  # (a wheel, `pip install .` or `pip wheel .`, builds them into the package instead: scikit-build-core)
  .venv/bin/python -m pip install --quiet --no-deps --no-build-isolation -C wheel.cmake=false -e .
  echo "$wanted" > "$stamp"
fi
if [ -f build/CMakeCache.txt ]; then
  echo "setup: build/ is configured; building what changed"  # (CMake configures again where its files changed)
  : > build.log
else
  .venv/bin/cmake -S . -B build -DPython3_EXECUTABLE="$PWD/.venv/bin/python" > build.log 2>&1 || { cat build.log; exit 1; }
fi
.venv/bin/cmake --build build -j 2 >> build.log 2>&1 || { cat build.log; exit 1; }
touch build/built.stamp  # cosim.engine.artifacts: the build is current
echo "FMUs built:" build/fmus/*.fmu
