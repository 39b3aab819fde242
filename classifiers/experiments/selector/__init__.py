"""The RL selector: learn to pick the grip to execute with MaskablePPO, judged on unseen objects.

>>> from classifiers.experiments.selector import run_selector
>>> report = run_selector("data/grips", "runs/selector", config)   # writes selector.json

Modules: ``policy`` (permutation-equivariant actor-critic), ``training`` (MaskablePPO on
``GripSelect-v0``), ``evaluation`` (exact expected success vs baselines on held-out objects),
``plots`` (learning curve).
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

from grip_env.config import Config

REPORT_FILE = "selector.json"

__all__ = ["REPORT_FILE", "run_selector"]


def run_selector(
    table_or_dir: Any,
    out_dir: str | Path,
    config: Config,
    policy: str = "set",
    timesteps: int | None = None,
    live: bool = False,
    progress: bool = True,
    recorded_only: bool = False,
) -> dict[str, Any]:
    """Train the selector on the training objects, evaluate it on the test objects.

    Writes ``out_dir/selector.json`` (the result of
    :func:`~classifiers.experiments.selector.evaluation.evaluate_selectors` plus a ``training``
    section),
    ``model.zip``, ``tb/`` and ``learning_curve.png``; returns the report. Live training
    is still evaluated on the dataset's recorded outcomes. ``recorded_only``: the retry task on
    the training objects whose trials are recorded (the training section says how many).
    """
    from classifiers.experiments.selector.data import check_grip_table
    from classifiers.experiments.selector.evaluation import evaluate_selectors
    from classifiers.experiments.selector.training import (
        CURVE_FILE,
        MODEL_FILE,
        check_policy,
        train_selector,
    )

    check_policy(policy)
    table = check_grip_table(table_or_dir)
    out = Path(out_dir)
    start = time.perf_counter()
    trained = train_selector(table, config, out, policy, timesteps, live, progress,
                             recorded_only)
    seconds = time.perf_counter() - start
    report = evaluate_selectors(trained.model, table, config)
    rewards = trained.rewards
    report["training"] = {
        "policy": policy,
        "timesteps": int(trained.model.num_timesteps),
        "backend": "live" if live else "replay",
        "seconds": round(seconds, 2),
        "episodes": len(rewards),
        "final_mean_reward": float(rewards[-100:].mean()) if len(rewards) else None,
        "model": MODEL_FILE,
        "learning_curve": CURVE_FILE,
        "tensorboard": "tb",
        "held_out_curve": [[int(t), round(v, 6)] for t, v in trained.held_out],
    }
    if trained.objects is not None:  # the retry task: the objects whose trials it replayed
        report["training"]["objects"] = {"used": len(trained.objects.objects),
                                         "of": trained.objects.total,
                                         "summary": trained.objects.summary()}
    (out / REPORT_FILE).write_text(json.dumps(report, indent=2))
    return report
