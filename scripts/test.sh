#!/usr/bin/env bash
# The test command: set up .venv if needed, check style, run the whole suite on 2 workers.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup.sh
.venv/bin/ruff check .
.venv/bin/python -m pytest -n 2 --durations=15 "$@"
