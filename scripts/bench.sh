#!/usr/bin/env bash
# The benchmarks behind BENCHMARKS.md (not part of the test command: they take minutes).
# Usage: bash scripts/bench.sh [pytest -k expression]
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup.sh
mkdir -p runs/bench
.venv/bin/python -m pytest tests/benchmarks -o addopts="" -p no:randomly --benchmark-enable \
    --benchmark-json=runs/bench/benchmarks.json ${1:+-k "$1"} -q
