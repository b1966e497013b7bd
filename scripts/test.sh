#!/usr/bin/env bash
# Sets up (scripts/setup.sh) and runs the test suite. Extra arguments go to pytest
# (e.g. -m slow for the long studies). Exits non-zero when a test fails or none ran.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# Debian's Chromium for the run report's browser test (tests/platform/test_html_report.py).
if ! command -v chromium > /dev/null 2>&1; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  { $SUDO apt-get update -qq && $SUDO apt-get install -y -qq chromium; } > apt.log 2>&1 \
    || { cat apt.log; echo "could not install chromium (needed by the browser test)" >&2; exit 1; }
fi
status=0
.venv/bin/python -m pytest -ra "$@" || status=$?
if [ "$status" -eq 5 ]; then
  echo "pytest collected no tests: failing the run" >&2
fi
# Every shipped scene's export in the other tools (OMSimulator from ../shared/peers, libcosim, Ecos, fmpy.ssp) at the steps it wrote
# for them, and as one FMU in fmpy, fmusim, OMSimulator, libcosim and under Wine; the FMUs under hostile use: random FMI call sequences under sanitizers, threads under
# TSan; and the wheel, installed outside the checkout, running a scene, its SSP and a cluster sweep.
if [ "$#" -eq 0 ]; then
  tools=0
  .venv/bin/python -m pytest -ra -m tools tests/platform/test_export_tools.py tests/platform/test_system_fmu_tools.py \
    || tools=$?
  if [ "$tools" -eq 5 ]; then echo "the tools stage collected no tests: failing the run" >&2; fi
  [ "$tools" -eq 0 ] || status=1
  bash scripts/fuzz.sh ci || status=1
  bash scripts/check_wheel.sh || status=1
fi
exit "$status"
