#!/usr/bin/env bash
# Builds the documentation site into site/ (mkdocs with mkdocstrings; warnings are errors).
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/mkdocs ] || bash scripts/setup.sh
NO_MKDOCS_2_WARNING=1 .venv/bin/mkdocs build --strict "$@"
echo "site: $PWD/site/index.html"
