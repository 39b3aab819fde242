#!/usr/bin/env bash
# Build the documentation site into docs/_build/html (set up .venv if needed). Warnings are errors,
# so a broken reference, a missing page or a failing generated page fails the build.
# Usage: bash scripts/docs.sh [more sphinx-build options, e.g. -E to reread every page]
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup.sh
.venv/bin/python -m sphinx -W --keep-going -b html "$@" docs docs/_build/html
