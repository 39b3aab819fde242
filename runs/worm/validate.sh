#!/usr/bin/env bash
# The cross-check of the regenerated standard dataset (resumes from crosscheck80.crosscheck/).
cd /work/wt-combo
while pgrep -f "calibrate --config configs/standard.yaml" > /dev/null; do sleep 5; done
date -u +"validate start %H:%M:%S" >> /work/main/runs/worm/validate.log
env PYTHONPATH=/work/wt-combo .venv/bin/python -c 'from grip_env.cli import main; main()' \
  validate standard --resimulate 100 --crosscheck 80 --workers 2 \
  --report /work/main/runs/worm/crosscheck80.json >> /work/main/runs/worm/validate.log 2>&1
echo "rc=$?" >> /work/main/runs/worm/validate.log
date -u +"validate end %H:%M:%S" >> /work/main/runs/worm/validate.log
