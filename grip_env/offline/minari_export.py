"""Episodes of ``GripSelect-v0`` (replay) written as a Minari dataset, for offline RL.

>>> from grip_env.offline import ExportPlan, export_minari
>>> dataset = export_minari(ExportPlan("grip-env/standard-uniform-v0", episodes_per_object=10))

Every episode is one object of the dataset's ``split`` (``"train"`` by default: the training
objects of the benchmark's standard split, so that an offline learner never sees a held-out
object), pinned with ``reset(options={"object_id": ...})``; the objects are visited in turn,
``episodes_per_object`` times each. The behaviour policy
(:class:`~grip_env.offline.behaviour.BehaviourPolicy`) picks a valid slot with its own generator
seeded by ``seed``; the environment is reset once with ``seed`` (the later resets continue its
generator), so one seed gives the same episodes, step for step.

What Minari lacks is kept inside the episode:

- the action mask: the observation is ``GripSelect-v0``'s own ``Dict(features, mask)``, so
  ``episode.observations["mask"][t]`` is the mask at step ``t``; with ``max_attempts > 1`` it
  also holds ``failed`` (the slots tried and failed so far in the episode);
- the reward's source: ``infos`` hold, per step, the object's index in the metadata's
  ``objects`` list (``object_index``), the executed ``slot``, its recorded ``success_rate``
  (successes / trials of the grip's recorded trials: replay draws the reward as a Bernoulli of
  it) and its ``q_c``; at the reset step slot is -1 and the rates NaN;
- the object: each episode's reset ``options`` (``object_id``).

The dataset's metadata holds what Minari expects (``env_spec``: the collecting environment;
``eval_env_spec``: the same environment on the held-out objects, ``split="test"``;
``ref_min_score`` / ``ref_max_score``: the exact expected returns of the uniform-random and the
oracle policy on the evaluation objects, :mod:`grip_env.offline.reference`; ``algorithm_name``,
``author``, ``code_permalink``, ``description``, ``requirements``) and grip-env's own record
(``grip_env``: behaviour policy, objects, split, seed, episodes per object, dataset checksum,
the reference returns on the training objects too), which the benchmark reads as the objects a
policy trained on the export has seen.
"""

from __future__ import annotations

import os
import shutil
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from grip_env.envs.observation import CandidateSet, candidate_sets
from grip_env.offline.behaviour import BehaviourPolicy
from grip_env.offline.reference import reference_returns

ENV_ID = "GripSelect-v0"
#: The key of grip-env's own record in the Minari metadata.
RECORD_KEY = "grip_env"
AUTHOR = "The grip-env authors"
DATA_FORMAT = "hdf5"
EXTRA_HINT = "the offline extra: pip install 'grip-env[offline]' (minari, d3rlpy)"
SPLITS = ("train", "test", "all")


@dataclass(frozen=True)
class ExportPlan:
    """What to export: the environment's data and split, the episodes and their policy."""

    dataset_id: str
    data: str = "standard"
    split: str = "train"
    episodes_per_object: int = 10
    policy: BehaviourPolicy = field(default_factory=lambda: BehaviourPolicy("uniform"))
    seed: int = 0
    max_attempts: int | None = None

    def __post_init__(self) -> None:
        if self.split not in SPLITS:
            raise ValueError(f"split must be one of {SPLITS}, got {self.split!r}")
        if self.episodes_per_object < 1:
            raise ValueError(f"episodes_per_object must be >= 1, got {self.episodes_per_object}")
        if self.seed < 0:
            raise ValueError(f"seed must be >= 0, got {self.seed}")

    def env_kwargs(self, split: str | None = None) -> dict[str, Any]:
        """The keyword arguments of the environment (JSON values: they go into its spec)."""
        data = self.data if self.data == "standard" else str(Path(self.data).resolve())
        kwargs: dict[str, Any] = {"data": data, "split": split or self.split}
        if self.max_attempts is not None:
            kwargs["max_attempts"] = int(self.max_attempts)
        return kwargs


def require_minari() -> Any:
    """The ``minari`` module, or ValueError naming the extra to install."""
    try:
        import minari
    except ImportError as exc:
        raise ValueError(f"exporting to Minari needs {EXTRA_HINT} ({exc})") from None
    return minari


def dataset_exists(dataset_id: str) -> bool:
    """Whether a local Minari dataset ``dataset_id`` exists (under ``MINARI_DATASETS_PATH``)."""
    from minari.storage import get_dataset_path

    return Path(get_dataset_path(dataset_id)).exists()


def check_dataset_id(dataset_id: str, overwrite: bool) -> None:
    """ValueError for an id Minari cannot parse, or one that exists (unless ``overwrite``)."""
    require_minari()
    from minari.dataset.minari_dataset import DATASET_ID_RE

    found = DATASET_ID_RE.fullmatch(dataset_id)
    if found is None or found.group("version") is None:
        raise ValueError(f"invalid Minari dataset id {dataset_id!r}: the form is "
                         f"[namespace/]name-v<version> (a namespace of two characters or "
                         f"more), e.g. grip-env/standard-uniform-v0")
    if dataset_exists(dataset_id) and not overwrite:
        raise ValueError(f"Minari dataset {dataset_id!r} already exists under "
                         f"{_datasets_root()}: give --overwrite to replace it, or another "
                         f"id")  # fmt: skip


def export_minari(
    plan: ExportPlan, *, overwrite: bool = False, dataset_sha256: str | None = None,
    code_version: str | None = None, author: str = AUTHOR,
) -> Any:
    """Collect ``plan``'s episodes and write them as the Minari dataset ``plan.dataset_id``.

    Returns the :class:`minari.MinariDataset`. Raises ValueError before writing anything for a
    bad plan, an id that exists (unless ``overwrite``) or a missing extra.
    """
    minari = require_minari()
    import gymnasium

    import grip_env  # noqa: F401  (registers GripSelect-v0)

    check_dataset_id(plan.dataset_id, overwrite)
    env = gymnasium.make(ENV_ID, **plan.env_kwargs())
    eval_env = gymnasium.make(ENV_ID, **plan.env_kwargs("test" if plan.split == "train"
                                                        else plan.split))  # fmt: skip
    try:
        ids, sets = _objects_and_sets(env)
        objects = tuple(o for o, found in zip(ids, sets, strict=True) if found.count)
        episodes = collect_episodes(env, plan, objects)
        train_refs = reference_returns(sets, env.unwrapped.max_attempts, env.unwrapped.trials)
        low, high = reference_returns(_objects_and_sets(eval_env)[1],
                                      eval_env.unwrapped.max_attempts,
                                      eval_env.unwrapped.trials)  # fmt: skip
        record = _record(plan, objects, train_refs, dataset_sha256, code_version,
                         env.unwrapped.trials)  # fmt: skip
        if overwrite and dataset_exists(plan.dataset_id):
            _delete(plan.dataset_id)
        with warnings.catch_warnings():  # the project publishes no e-mail address
            warnings.filterwarnings("ignore", message="`author_email` is set to None")
            dataset = minari.create_dataset_from_buffers(
                dataset_id=plan.dataset_id, buffer=episodes, env=env, eval_env=eval_env,
                algorithm_name=f"behaviour policy: {plan.policy.describe()}", author=author,
                code_permalink=_permalink(code_version), ref_min_score=low, ref_max_score=high,
                description=_description(plan, objects, eval_env.unwrapped.object_ids),
                data_format=DATA_FORMAT, requirements=["grip-env[offline]"],
            )  # fmt: skip
        dataset.storage.update_metadata({RECORD_KEY: record})
    finally:
        env.close()
        eval_env.close()
    return dataset


def collect_episodes(env: Any, plan: ExportPlan, objects: Sequence[str]) -> list[Any]:
    """``plan.episodes_per_object`` episodes of each object in turn, as Minari episode buffers."""
    from minari.data_collector import EpisodeBuffer

    rng = np.random.default_rng(plan.seed)
    index = {object_id: i for i, object_id in enumerate(objects)}
    buffers, first = [], True
    for _ in range(plan.episodes_per_object):
        for object_id in objects:
            seed = plan.seed if first else None
            observation, _ = env.reset(seed=seed, options={"object_id": object_id})
            first = False
            steps = _run_episode(env, plan.policy, rng, observation, index[object_id])
            buffers.append(EpisodeBuffer(id=len(buffers), seed=seed,
                                         options={"object_id": object_id}, **steps))  # fmt: skip
    return buffers


def _run_episode(env: Any, policy: BehaviourPolicy, rng: np.random.Generator,
                 observation: dict[str, Any], object_index: int) -> dict[str, Any]:  # fmt: skip
    """One episode's arrays: T + 1 observations and infos, T actions, rewards and flags."""
    observations, infos = [observation], [_info(object_index, -1, None)]
    actions, rewards, terminations, truncations = [], [], [], []
    done = False
    while not done:
        action = policy.act(observation, rng)
        observation, reward, terminated, truncated, info = env.step(action)
        observations.append(observation)
        infos.append(_info(object_index, action, info))
        actions.append(action)
        rewards.append(float(reward))
        terminations.append(bool(terminated))
        truncations.append(bool(truncated))
        done = terminated or truncated
    return {
        "observations": {key: np.stack([o[key] for o in observations])
                         for key in observations[0]},  # features, mask (and failed: retries)
        "actions": np.asarray(actions, dtype=np.int64), "rewards": rewards,
        "terminations": terminations, "truncations": truncations,
        "infos": {key: np.asarray([i[key] for i in infos]) for key in infos[0]},
    }  # fmt: skip


def _info(object_index: int, slot: int, info: dict[str, Any] | None) -> dict[str, Any]:
    """The numeric info Minari stores per step (the same keys at reset and at every step)."""
    rate = np.nan if info is None or info["success_rate"] is None else info["success_rate"]
    q_c = np.nan if info is None or info["Q_C"] is None else info["Q_C"]
    return {"object_index": np.int64(object_index), "slot": np.int64(slot),
            "success_rate": np.float64(rate), "q_c": np.float64(q_c)}  # fmt: skip


def _objects_and_sets(env: Any) -> tuple[tuple[str, ...], list[CandidateSet]]:
    """The environment's object ids and their candidate sets (as its observations show them)."""
    base = env.unwrapped
    frames = [base.backend.candidates(o) for o in base.object_ids]
    return base.object_ids, candidate_sets(base.object_ids, frames, base.scaler,
                                           base.max_candidates)  # fmt: skip


def _record(plan: ExportPlan, objects: Sequence[str], train_refs: tuple[float, float],
            dataset_sha256: str | None, code_version: str | None,
            trials: int = 0) -> dict[str, Any]:  # fmt: skip
    drawn = (f"the grip's recorded trial k, one k in 0..{trials - 1} drawn an episode and "
             "replayed by every attempt of it (the shared draws)" if trials else
             "a Bernoulli draw of the grip's recorded success rate (successes / trials)")
    return {
        "behaviour_policy": {"name": plan.policy.name, "epsilon": plan.policy.epsilon,
                             "description": plan.policy.describe()},
        "objects": sorted(objects), "split": plan.split, "data": plan.data,
        "episodes_per_object": plan.episodes_per_object, "seed": plan.seed,
        "env_kwargs": plan.env_kwargs(), "dataset_sha256": dataset_sha256,
        "code_version": code_version,
        "train_reference_returns": {"random": train_refs[0], "oracle": train_refs[1]},
        "reward": f"1 when the executed grip holds, 0 when it drops: {drawn}, as replay "
                  "executes it",
    }  # fmt: skip


def _description(plan: ExportPlan, objects: Sequence[str], held_out: Sequence[str]) -> str:
    retry = ", failed" if (plan.max_attempts or 1) > 1 else ""
    return (f"{len(objects)} objects of the grip-env dataset {plan.data!r} (split "
            f"{plan.split!r}), {plan.episodes_per_object} episodes each of {ENV_ID} (replay), "
            f"logged by the behaviour policy: {plan.policy.describe()}, seed {plan.seed}. The "
            f"observation is the environment's Dict(features, mask{retry}): the action mask "
            f"is observations['mask']. The reference scores are the exact expected returns of the "
            f"uniform-random and the oracle pick on the {len(held_out)} evaluation objects "
            f"(eval_env_spec).")  # fmt: skip


def _permalink(code_version: str | None) -> str:
    return f"grip-env {code_version}" if code_version else "grip-env (version unknown)"


def _delete(dataset_id: str) -> None:
    """Remove a local Minari dataset (``minari.delete_dataset`` without its print)."""
    from minari.storage import get_dataset_path

    shutil.rmtree(get_dataset_path(dataset_id))


def _datasets_root() -> str:
    return os.environ.get("MINARI_DATASETS_PATH") or str(Path.home() / ".minari" / "datasets")
