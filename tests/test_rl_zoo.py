"""RL Zoo trains PPO on GripSelect-v0 from the shipped hyper-parameter file."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from grip_env.rl_zoo import hyperparameter_file, load_hyperparameters

ROOT = Path(__file__).resolve().parents[1]


def test_shipped_hyperparameters_name_the_environment():
    params = load_hyperparameters("ppo")["GripSelect-v0"]
    assert params["policy"] == "MultiInputPolicy" and params["n_timesteps"] > 0
    with pytest.raises(ValueError, match="ppo_mask"):
        hyperparameter_file("ppo_mask")


@pytest.mark.slow
def test_rl_zoo_trains_a_few_hundred_steps(generated_dataset_dir, tmp_path):
    pytest.importorskip("rl_zoo3")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get(
        "PYTHONPATH", "")])}  # fmt: skip
    command = [sys.executable, "-m", "rl_zoo3.train", "--algo", "ppo", "--env", "GripSelect-v0",
               "--gym-packages", "grip_env", "--conf-file", "grip_env.rl_zoo.ppo",
               "--env-kwargs", f"data:'{generated_dataset_dir}'", "-n", "256",
               "--eval-freq", "-1", "--seed", "0", "--log-folder", str(tmp_path / "logs")]
    done = subprocess.run(command, cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    (model,) = (tmp_path / "logs" / "ppo").glob("GripSelect-v0_*/GripSelect-v0.zip")
    from stable_baselines3 import PPO

    assert PPO.load(model, device="cpu").num_timesteps >= 256
    # trained on split "all" (the env's default): the benchmark reads args.yml and refuses it
    from cli_runs import assert_refused, cli

    assert_refused(*cli("benchmark", model, "--data", generated_dataset_dir, "--out",
                        tmp_path / "never"), "args.yml", "in-sample")  # fmt: skip
    assert not (tmp_path / "never").exists()
