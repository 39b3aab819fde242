#!/usr/bin/env bash
# The main job: set up .venv if needed, then run the whole study on the embedded default config.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup.sh
.venv/bin/grip-env study --config configs/default.yaml --out "${1:-runs/default}"
