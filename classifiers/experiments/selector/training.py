"""Training the RL selector with sb3-contrib's MaskablePPO on ``GripSelect-v0``.

``policy="set"`` uses :class:`~classifiers.experiments.selector.policy.CandidateSetPolicy` (one
shared scorer
per candidate, permutation-equivariant); ``policy="flat"`` is MaskablePPO's stock
``"MultiInputPolicy"`` (the (K, F) features and the mask flattened into one MLP), for comparison.

The replay backend trains on the training objects of the object-level split that the classifiers
use (``config.learning.test_fraction`` and ``config.learning.seed``); ``live=True`` executes the
grips in PyBullet instead (slow: one simulated trial per step).

The PPO hyper-parameters (``n_envs``, ``rollout_steps``, ``batch_size``, ``n_epochs``,
``learning_rate``, ``gamma``, ``ent_coef``) are the ``selector`` section of the config; nothing
here has a default of its own. With the replay backend, every rollout also scores the current
policy's deterministic first pick on the held-out objects (the ones ``selector.json`` reports) and
logs it to TensorBoard as ``eval/held_out_first_pick_success``, beside the constant
``eval/best_qc`` and ``eval/oracle`` of the same objects.

``config.selector.reward`` chooses what a pick earns: ``"success"`` (the environment's 0/1 draw),
``"expected_success"`` (:class:`ExpectedSuccessReward`: the picked grip's recorded success rate,
the expectation of that draw: a variance-reduction baseline) or ``"robustness"``
(:class:`RobustnessReward`: the picked grip's recorded ``robustness_mean`` divided by
``sim.reference_level_g``, so 1 means holding the reference level on average).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import pandas as pd
import torch as th
from sb3_contrib import MaskablePPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import DummyVecEnv

import grip_env  # noqa: F401  (registers GripSelect-v0)
from classifiers.experiments.selector.data import check_grip_table
from classifiers.experiments.selector.plots import plot_learning_curve
from classifiers.experiments.selector.policy import CandidateSetPolicy
from classifiers.experiments.selector.recorded import (
    RecordedTrainingObjects,
    retry_training_objects,
)
from grip_env.config import Config, SelectorConfig

POLICIES: tuple[str, ...] = ("set", "flat")
ENV_ID = "GripSelect-v0"
N_ENVS = SelectorConfig().n_envs
MODEL_FILE = "model.zip"
CURVE_FILE = "learning_curve.png"


def check_policy(policy: str) -> str:
    """``policy`` if it is one of :data:`POLICIES`, else ValueError."""
    if policy not in POLICIES:
        raise ValueError(f"policy must be one of {POLICIES}, got {policy!r}")
    return policy


class RobustnessReward(gymnasium.Wrapper):
    """Replace a valid pick's reward by its grip's ``robustness_mean / reference_g``."""

    def __init__(self, env: gymnasium.Env, table: pd.DataFrame, reference_g: float) -> None:
        super().__init__(env)
        if "robustness_mean" not in table.columns:
            raise ValueError("selector.reward 'robustness' needs a dataset with robustness_mean "
                             "(regenerate it with the graded outcome)")  # fmt: skip
        if not reference_g > 0:
            raise ValueError(f"reference level must be positive, got {reference_g!r}")
        values = table["robustness_mean"].to_numpy(float) / float(reference_g)
        self._reward = dict(zip(table["grip_id"].tolist(), values.tolist(), strict=True))

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """The wrapped step with the pick's robustness as its reward."""
        observation, reward, terminated, truncated, info = self.env.step(action)
        if not info.get("invalid_action"):
            reward = self._reward[info["grip_id"]]
        return observation, float(reward), terminated, truncated, info


class ExpectedSuccessReward(gymnasium.Wrapper):
    """Replace a valid pick's 0/1 reward by its expectation: the grip's recorded success rate.

    A variance-reduction baseline (Rao-Blackwellisation of the replayed Bernoulli draw): every
    policy's expected return is unchanged, since the environment draws success with exactly this
    probability, but a pick no longer earns 1 or 0 by the luck of one trial, so the policy
    gradient is far less noisy. It needs recorded outcomes (replay) and one attempt an episode
    (with more, whether the episode goes on is itself the draw it averages out).
    """

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """The wrapped step with the pick's recorded success rate as its reward."""
        observation, reward, terminated, truncated, info = self.env.step(action)
        if not info.get("invalid_action"):
            rate = info.get("success_rate")
            if rate is None:
                raise ValueError("selector.reward 'expected_success' needs recorded success "
                                 "rates (the replay backend)")  # fmt: skip
            reward = rate
        return observation, float(reward), terminated, truncated, info


#: Rewards that need recorded outcomes, hence the replay backend.
RECORDED_REWARDS = ("robustness", "expected_success")


def check_reward(config: Config, live: bool) -> str:
    """The configured reward; robustness and expected success need recorded outcomes (replay),
    and expected success one attempt an episode."""
    reward = config.selector.reward
    if reward in RECORDED_REWARDS and live:
        raise ValueError(f"selector.reward {reward!r} needs the replay backend (live trials "
                         "report success only)")  # fmt: skip
    if reward == "expected_success" and config.selector.max_attempts > 1:
        raise ValueError("selector.reward 'expected_success' needs selector.max_attempts 1, got "
                         f"{config.selector.max_attempts}")  # fmt: skip
    return reward


def make_selector_env(
    data: pd.DataFrame | None,
    config: Config,
    split: str = "train",
    n_envs: int = N_ENVS,
    seed: int = 0,
    objects: tuple[str, ...] | None = None,
) -> DummyVecEnv:
    """``n_envs`` monitored ``GripSelect-v0`` copies in a DummyVecEnv (replay, or live if None),
    rewarded as ``config.selector.reward`` says; ``objects`` (replay) draws the episodes from
    these objects only, replaying their trials by index (the retry task's recorded objects)."""

    reward = check_reward(config, data is None)
    where: dict[str, Any] = {"split": split}
    if objects is not None:
        where = {"split": "all", "objects": list(objects), "replay": "trial"}

    def factory(rank: int) -> Any:
        def build() -> gymnasium.Env:
            env = gymnasium.make(ENV_ID, data=data, config=config, **where)
            if reward == "robustness":
                env = RobustnessReward(env, data, config.sim.reference_level_g)
            elif reward == "expected_success":
                env = ExpectedSuccessReward(env)
            env.reset(seed=seed + rank)
            return Monitor(env)

        return build

    return DummyVecEnv([factory(rank) for rank in range(n_envs)])


def make_selector_model(
    env: DummyVecEnv, policy: str, seed: int = 0, tensorboard_log: str | Path | None = None,
    timesteps: int | None = None, settings: SelectorConfig | None = None,
) -> MaskablePPO:
    """A fresh MaskablePPO on ``env`` with the ``"set"`` or ``"flat"`` policy.

    Hyper-parameters come from ``settings`` (default: the ``selector`` section's defaults). A
    rollout is ``settings.rollout_steps`` over all envs, shortened when ``timesteps`` asks for
    less (so a short live run does not simulate a full rollout it will never use).
    """
    check_policy(policy)
    settings = settings or SelectorConfig()
    policy_class = CandidateSetPolicy if policy == "set" else "MultiInputPolicy"
    rollout = settings.rollout_steps if timesteps is None else min(settings.rollout_steps,
                                                                   timesteps)
    n_steps = max(16, rollout // env.num_envs)
    policy_kwargs = {"context": settings.context} if policy == "set" else None
    return MaskablePPO(
        policy_class,
        env,
        policy_kwargs=policy_kwargs,
        learning_rate=settings.learning_rate,
        n_steps=n_steps,
        batch_size=min(settings.batch_size, n_steps * env.num_envs),
        n_epochs=settings.n_epochs,
        gamma=settings.gamma,
        ent_coef=settings.ent_coef,
        seed=seed,
        tensorboard_log=None if tensorboard_log is None else str(tensorboard_log),
        verbose=0,
    )


class EpisodeRecorder(BaseCallback):
    """Keeps every finished episode's reward and the timestep it ended at (from ``Monitor``)."""

    def __init__(self) -> None:
        super().__init__()
        self.timesteps: list[int] = []
        self.rewards: list[float] = []

    def _on_step(self) -> bool:
        for info in self.locals.get("infos", ()):
            episode = info.get("episode")
            if episode is not None:
                self.timesteps.append(self.num_timesteps)
                self.rewards.append(float(episode["r"]))
        return True


class HeldOutEvaluation(BaseCallback):
    """After each rollout, the policy's first-pick success on the held-out objects, to
    TensorBoard (``eval/held_out_first_pick_success``) and to :attr:`curve`."""

    def __init__(self, table: pd.DataFrame, config: Config) -> None:
        super().__init__()
        from classifiers.experiments.selector.evaluation import held_out_candidate_sets

        self.sets = held_out_candidate_sets(table, config)
        self.max_attempts = config.selector.max_attempts
        self.curve: list[tuple[int, float]] = []
        rates = [s.success_rate[: s.count] for s in self.sets]
        self.reference = {
            "eval/best_qc": float(np.mean([r[np.argsort(s.rows["Q_C"].to_numpy(float),
                                                        kind="stable")[0]]
                                           for s, r in zip(self.sets, rates, strict=True)])),
            "eval/oracle": float(np.mean([r.max() for r in rates])),
        } if self.sets else {}  # fmt: skip

    def _on_step(self) -> bool:
        return True

    def _on_rollout_end(self) -> None:
        if not self.sets:
            return
        from classifiers.experiments.selector.evaluation import policy_orders

        picks = policy_orders(self.model, self.sets, 1)
        value = float(np.mean([s.success_rate[order[0]] for s, order in zip(self.sets, picks,
                                                                             strict=True)]))
        self.curve.append((self.num_timesteps, value))
        self.logger.record("eval/held_out_first_pick_success", value)
        for key, reference in self.reference.items():
            self.logger.record(key, reference)


@dataclass(frozen=True)
class SelectorTraining:
    """What :func:`train_selector` returns: the model and its curves.

    Attributes:
        model: the trained MaskablePPO (also saved as ``model.zip``).
        timesteps, rewards: each finished training episode's end timestep and reward.
        held_out: ``(timestep, first-pick success on the held-out objects)`` after each
            rollout (replay only; empty for live training).
    """

    model: MaskablePPO
    timesteps: np.ndarray
    rewards: np.ndarray
    held_out: tuple[tuple[int, float], ...] = ()
    objects: RecordedTrainingObjects | None = None


@contextmanager
def torch_threads(count: int) -> Iterator[None]:
    """Run torch on ``count`` threads (small networks are fastest single-threaded)."""
    previous = th.get_num_threads()
    th.set_num_threads(count)
    try:
        yield
    finally:
        th.set_num_threads(previous)


def train_selector(
    data: Any,
    config: Config,
    out_dir: str | Path,
    policy: str = "set",
    timesteps: int | None = None,
    live: bool = False,
    progress: bool = True,
    recorded_only: bool = False,
) -> SelectorTraining:
    """Train a selector on the training objects; writes ``model.zip``, ``tb/`` and the curve PNG.

    Args:
        data: dataset directory/file or DataFrame (replay); ignored when ``live``.
        config: grip-env configuration (``selector`` and ``learning`` sections).
        out_dir: output directory.
        policy: ``"set"`` (permutation-equivariant) or ``"flat"`` (stock MultiInputPolicy).
        timesteps: environment steps (default ``config.selector.timesteps``).
        live: execute grips in PyBullet instead of replaying recorded outcomes.
        progress: show a progress bar.
        recorded_only: the retry task (``selector.max_attempts > 1``) on the training objects
            whose trials are recorded only, the others left out and counted
            (:func:`~classifiers.experiments.selector.recorded.retry_training_objects`);
            without it such objects are refused.

    Returns:
        The model with its episode curve and its held-out evaluations.
    """
    check_policy(policy)
    settings = config.selector
    steps = settings.timesteps if timesteps is None else timesteps
    if int(steps) != steps or steps < 1:
        raise ValueError(f"timesteps must be a positive integer, got {timesteps!r}")
    table = None if live else check_grip_table(data)
    recorded = None if table is None else retry_training_objects(table, config, recorded_only)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    env = make_selector_env(table, config, "train", 1 if live else settings.n_envs, settings.seed,
                            None if recorded is None else recorded.objects)  # fmt: skip
    callbacks: list[BaseCallback] = [EpisodeRecorder()]
    if table is not None:
        callbacks.append(HeldOutEvaluation(table, config))
    with torch_threads(1):
        model = make_selector_model(env, policy, settings.seed, out / "tb", timesteps=int(steps),
                                    settings=settings)  # fmt: skip
        model.learn(int(steps), callback=callbacks, progress_bar=progress,
                    tb_log_name=f"selector_{policy}")  # fmt: skip
    model.save(out / MODEL_FILE)
    from classifiers.experiments.benchmark.provenance import write_agent_record

    subset = {} if recorded is None else {"split": "train", "trials_recorded": recorded.summary()}
    write_agent_record(out / MODEL_FILE, env, **subset)  # model.json: the objects trained on
    recorder = callbacks[0]
    baselines = None
    if table is not None:
        from classifiers.experiments.selector.evaluation import training_baselines

        baselines = training_baselines(table, config,
                                       None if recorded is None else recorded.objects)
    plot_learning_curve(recorder.timesteps, recorder.rewards, out / CURVE_FILE,
                        baselines=baselines)  # fmt: skip
    env.close()
    held_out = tuple(callbacks[1].curve) if table is not None else ()
    return SelectorTraining(model, np.asarray(recorder.timesteps), np.asarray(recorder.rewards),
                            held_out, recorded)  # fmt: skip
