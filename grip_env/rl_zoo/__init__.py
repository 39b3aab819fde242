"""Hyper-parameters for RL Zoo (``rl_zoo3``), which trains SB3 agents from a YAML file.

``ppo.yml`` (beside this file) trains PPO on ``GripSelect-v0`` with the selector section's
defaults; ``--conf-file grip_env.rl_zoo.ppo`` reads the same file from the installed package::

    python -m rl_zoo3.train --algo ppo --env GripSelect-v0 --gym-packages grip_env \\
        --conf-file grip_env.rl_zoo.ppo --env-kwargs data:"'runs/default/dataset'"

RL Zoo's algorithms (rl_zoo3 2.9) do not include sb3-contrib's MaskablePPO, so the zoo's agent
is plain PPO: it sees the mask as part of the observation and a masked slot earns
``invalid_action_reward`` and ends the episode. The masked, permutation-equivariant selector is
``grip-env select`` (:mod:`classifiers.experiments.selector`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

HERE = Path(__file__).parent


def hyperparameter_file(algo: str) -> Path:
    """The shipped YAML of ``algo``; unknown → ValueError naming the shipped ones."""
    path = HERE / f"{algo}.yml"
    if not path.is_file():
        shipped = sorted(p.stem for p in HERE.glob("*.yml"))
        raise ValueError(f"no RL Zoo hyper-parameters for {algo!r}; shipped: {shipped}")
    return path


def load_hyperparameters(algo: str) -> dict[str, Any]:
    """``{env_id: hyper-parameters}`` of ``algo``, as RL Zoo reads a YAML file (``!!float`` tags
    included)."""
    return yaml.safe_load(hyperparameter_file(algo).read_text())
