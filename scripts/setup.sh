#!/usr/bin/env bash
# Create .venv when missing and install the project into it (torch's CPU wheel first, so that no
# CUDA build is pulled). Sourced by study.sh and test.sh; re-running is cheap when nothing changed.
# The work runs in a subshell: sourcing this file leaves the caller's shell options (set -euo
# pipefail) and working directory as they were, and a failure is the source's exit status.
(
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
PYTHON=${PYTHON:-python3.11}
command -v "$PYTHON" >/dev/null 2>&1 || PYTHON=python3
if [ ! -x .venv/bin/python ]; then
    "$PYTHON" -m venv .venv
fi
stamp=.venv/.grip-env-installed
want="$(cat pyproject.toml scripts/setup.sh | sha256sum | cut -d' ' -f1)"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
    .venv/bin/python -m pip install --quiet --upgrade pip
    .venv/bin/python -m pip install --quiet torch==2.13.0
    .venv/bin/python -m pip install --quiet -e ".[dev,cluster,docs,mujoco]"
    # the offline extra (pyproject) without d3rlpy's pin of gymnasium==1.0.0: its other
    # requirements, then d3rlpy itself with --no-deps (it runs on gymnasium 1.4). d3rlpy imports
    # the old gym; gym goes in without gym_notices, whose banner every SB3 import would print
    .venv/bin/python -m pip install --quiet "minari[hdf5]>=0.5.4" structlog colorama \
        dataclasses-json
    .venv/bin/python -m pip install --quiet --no-deps "d3rlpy>=2.8.1" "gym==0.26.2"
    .venv/bin/python -m pip uninstall --quiet --yes gym_notices 2>/dev/null || true
    echo "$want" > "$stamp"
fi
)
