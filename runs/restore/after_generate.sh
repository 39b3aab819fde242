#!/usr/bin/env bash
# After the regeneration: pack a copy, put it in the worktree's package data, run the cross-check.
set -euo pipefail
PY=/work/main/.venv/bin/python
rm -rf /work/runs/restore/standard
cp -r /work/main/runs/standard-restore /work/runs/restore/standard
PYTHONPATH=/work/wt-restore $PY -m grip_env.dataset.packing /work/runs/restore/standard
D=/work/wt-restore/grip_env/data/standard
rm -rf $D/grips $D/manifest.json $D/objects.parquet
cp -r /work/runs/restore/standard/grips /work/runs/restore/standard/manifest.json /work/runs/restore/standard/objects.parquet $D/
rm -rf /work/runs/restore/crosscheck80.crosscheck
cp -r /work/runs/worm-checkpoint/crosscheck80.crosscheck /work/runs/restore/crosscheck80.crosscheck
cd /work/wt-restore
PYTHONPATH=/work/wt-restore $PY -c "import sys; from grip_env.cli import main; sys.argv=['grip-env','validate','standard','--resimulate','100','--crosscheck','80','--workers','2','--report','/work/runs/restore/crosscheck80.json']; sys.exit(main())"
