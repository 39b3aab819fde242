"""``--conf-file grip_env.rl_zoo.ppo``: RL Zoo reads the module's ``hyperparams`` (``ppo.yml``)."""

from __future__ import annotations

from grip_env.rl_zoo import load_hyperparameters

hyperparams = load_hyperparameters("ppo")
