"""Methods as score tables: the analytic baselines, and loaders for a user's method.

A method gives, for each held-out object and run (``seed``), a score per candidate (higher =
pick first) or one chosen index (scored 1 for the choice, 0 for the rest). Every loader returns a
long table ``method, seed, object_id, candidate, score`` (:data:`SCORE_COLUMNS`), the input of
:func:`classifiers.experiments.benchmark.selection.selection_metrics`.

- baselines (:func:`baseline_scores`): ``best_qc`` (lowest Q_C first), ``best_qg`` (lowest Q_G),
  ``epsilon`` (highest Ferrari-Canny epsilon), ``random`` (all candidates tied: the exact
  expectation of a uniform pick) and ``oracle`` (highest recorded success rate, ties by
  robustness);
- an SB3 zip (:func:`sb3_scores`): MaskablePPO or PPO trained on ``GripSelect-v0``; the score is
  the policy's probability of each valid slot on the object's first observation, so the top-1 is
  the deterministic action (masked, for PPO as for MaskablePPO);
- a saved model (:func:`saved_model_scores`): a skops file, or a model ``grip-env train`` saved
  (any of its files, as ``grip-env predict`` takes them), taking the candidate table; scores
  are ``decision_function``, else ``P(success)``, else ``predict`` (a regressor, a ranker);
- a Python entry point ``module:function`` (:func:`entry_point_scores`): called with one
  object's candidate table (outcome columns removed, rows in slot order) and, when it takes a
  ``seed`` argument, once per training seed of the split; or a class, made once per run
  (with ``seed=`` when its ``__init__`` takes one) and its instance called on each table;
  what it returns is read by :mod:`classifiers.experiments.benchmark.outputs`.
"""

from __future__ import annotations

import functools
import importlib
import inspect
import sys
import zipfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from classifiers.experiments.benchmark.outputs import choice_scores
from grip_env.columns import OUTCOMES, ROBUSTNESS, TRIAL_ROBUSTNESS_PREFIX, TRIAL_SUCCESS_PREFIX
from grip_env.envs.observation import CandidateSet

SCORE_COLUMNS = ("method", "seed", "object_id", "candidate", "score")
BASELINES = ("best_qc", "best_qg", "epsilon", "random", "oracle")
HIDDEN_COLUMNS = (*OUTCOMES, *ROBUSTNESS)
SCORE_FILES = ("classifiers/scores.parquet", "images/scores.parquet", "selector/scores.parquet",
               "selector_retry/scores.parquet")
#: Per-trial outcome columns (``trial_success_k``, ``trial_robustness_k``) are hidden as well.
HIDDEN_PREFIXES = (TRIAL_SUCCESS_PREFIX, TRIAL_ROBUSTNESS_PREFIX)


def hidden_columns(columns: Sequence[str]) -> list[str]:
    """The outcome columns among ``columns``: what a method must not see."""
    return [c for c in columns if c in HIDDEN_COLUMNS or str(c).startswith(HIDDEN_PREFIXES)]


#: Learned-model names that are the baselines again (rank_qc is best_qc with calibrated units,
#: random a sampled stand-in for the exact random pick): left out of a study's leaderboard.
DUPLICATES = ("_rank_qc", "_rank_qg", "_random")


def score_frame(method: str, seed: int, candidates: pd.DataFrame, score: Any) -> pd.DataFrame:
    """A score table of one run from one score per row of ``candidates``."""
    return pd.DataFrame({"method": method, "seed": int(seed),
                         "object_id": candidates["object_id"].to_numpy(),
                         "candidate": candidates["candidate"].to_numpy(),
                         "score": np.asarray(score, dtype=float)})  # fmt: skip


def baseline_scores(candidates: pd.DataFrame, grasp: Any = None) -> pd.DataFrame:
    """Score tables of the analytic baselines (one run each)."""
    from grip_env.planning.epsilon import epsilon_quality

    oracle = candidates.assign(r=candidates.get("robustness_mean", 0.0)).sort_values(
        ["object_id", "success_rate", "r"], kind="mergesort")  # fmt: skip
    order = pd.Series(oracle.groupby("object_id").cumcount().to_numpy(), index=oracle.index)
    scores = {
        "best_qc": -candidates["Q_C"].to_numpy(float),
        "best_qg": -candidates["Q_G"].to_numpy(float),
        "epsilon": epsilon_quality(candidates, grasp),
        "random": np.zeros(len(candidates)),
        "oracle": order.loc[candidates.index].to_numpy(float),
    }
    return pd.concat([score_frame(n, 0, candidates, s) for n, s in scores.items()],
                     ignore_index=True)  # fmt: skip


def public_rows(found: CandidateSet) -> pd.DataFrame:
    """The candidate table a method sees: slot order, outcome columns removed."""
    rows = found.rows.drop(columns=hidden_columns(list(found.rows.columns)))
    return rows.reset_index(drop=True)


# ------------------------------------------------------------------ entry points
def load_entry_point(spec: str) -> Callable[..., Any]:
    """The function named by ``module:function``, imported as pytest and uvicorn import: the
    current directory first on ``sys.path``, so ``mysel:pick`` finds ``./mysel.py``."""
    module_name, sep, attribute = spec.partition(":")
    if not sep or not module_name or not attribute:
        raise ValueError(f"an entry point is 'module:function', got {spec!r}")
    folder = str(Path.cwd())
    if folder not in sys.path:
        sys.path.insert(0, folder)
    importlib.invalidate_caches()  # a module written since this process looked at the folder
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name is None or not f"{module_name}.".startswith(f"{exc.name}."):
            raise ValueError(f"importing {module_name!r} for {spec!r} failed: {exc}") from None
        raise ValueError(_no_module(spec, module_name, folder)) from None
    except Exception as exc:  # the user's module failing as it loads: bad input, in one line
        raise ValueError(f"importing {module_name!r} for {spec!r} failed: "
                         f"{type(exc).__name__}: {exc}") from None  # fmt: skip
    function = getattr(module, attribute, None)
    if not callable(function) and not is_policy(function):
        raise ValueError(f"{spec!r}: {module_name} has no function {attribute!r} (nor a policy "
                         f"object with predict(observation))")  # fmt: skip
    return function


def is_policy(selector: Any) -> bool:
    """Whether ``selector`` is an observation policy: an object (not a class) with a
    ``predict(observation)`` method, as SB3's and d3rlpy's policies have."""
    return not inspect.isclass(selector) and callable(getattr(selector, "predict", None))


def _no_module(spec: str, module_name: str, folder: str) -> str:
    """One line: the module not found, where it was looked for, and the expected form."""
    bare = module_name.removesuffix(".py")
    path = bare.replace(".", "/")
    hint = (f" (name the module without '.py': '{bare}:{spec.partition(':')[2]}')"
            if bare != module_name else "")  # fmt: skip
    return (f"no module {module_name!r} for the method {spec!r}: looked in the current folder "
            f"{folder} (for {path}.py or {path}/__init__.py) and the installed packages; a "
            f"function method is 'module:function', run from the folder that holds the module "
            f"or with the module installed{hint}")


def entry_point_scores(spec: str, sets: Sequence[CandidateSet], seeds: Sequence[int],
                       name: str) -> pd.DataFrame:  # fmt: skip
    """Score tables of a ``module:function`` method (one run, or one per seed when it takes a
    ``seed`` argument). A class is a selector too: made once per run (``Class(seed=...)`` when
    its ``__init__`` takes ``seed``, else ``Class()``), its instance called on each object."""
    function = load_entry_point(spec)
    seeded = callable(function) and "seed" in inspect.signature(function).parameters
    frames = []
    for seed in (seeds if seeded else (0,)):
        pick = _selector(function, spec, int(seed) if seeded else None)
        if is_policy(pick):
            frames.append(policy_scores(pick, sets, int(seed), name, spec))
            continue
        for found in sets:
            rows = public_rows(found)
            where = f"{spec} on object {found.object_id!r}"
            try:
                output = pick(rows)
            except Exception as exc:  # the user's code: its failure is bad input, in one line
                raise ValueError(f"{where} failed: {type(exc).__name__}: {exc}") from None
            scores = choice_scores(output, found.count, where)
            frames.append(score_frame(name, seed, _slots(found), scores))
    return pd.concat(frames, ignore_index=True)


def _selector(function: Callable[..., Any], spec: str, seed: int | None) -> Callable[..., Any]:
    """What is called on each object's table: the function (with ``seed`` bound), or an
    instance of the class (made with ``seed`` when it takes one)."""
    if not inspect.isclass(function):
        return function if seed is None else functools.partial(function, seed=seed)
    try:
        instance = function() if seed is None else function(seed=seed)
    except Exception as exc:  # the user's class failing as it is made: bad input, in one line
        raise ValueError(f"{spec}: making the selector failed: {type(exc).__name__}: "
                         f"{exc}") from None  # fmt: skip
    if not callable(instance) and not is_policy(instance):
        raise ValueError(f"{spec} is a class whose instances are not callable: give it a "
                         f"__call__(self, table) returning scores or one row index, or a "
                         f"predict(self, observation) returning a slot")  # fmt: skip
    return instance


# ------------------------------------------------------------------ observation policies
def check_policy_spaces(policy: Any, sets: Sequence[CandidateSet], spec: str) -> None:
    """ValueError when a policy declares an ``action_space`` (or ``observation_space``) that is
    not ``GripSelect-v0``'s on this split (one without them is taken as it is)."""
    from gymnasium import spaces

    k, width = sets[0].features.shape
    action = getattr(policy, "action_space", None)
    if action is not None and not (isinstance(action, spaces.Discrete) and int(action.n) == k):
        raise ValueError(f"{spec}: action space {action} does not match the split's "
                         f"GripSelect-v0 action space Discrete({k})")  # fmt: skip
    observation = getattr(policy, "observation_space", None)
    if observation is not None and not select_observation_space(observation, k, width):
        raise ValueError(f"{spec}: observation space {observation} does not match the split's "
                         f"GripSelect-v0 Dict(features=({k}, {width}), mask=({k},)[, "
                         f"failed=({k},)])")  # fmt: skip


def select_observation_space(observation: Any, k: int, width: int) -> bool:
    """Whether ``observation`` is ``GripSelect-v0``'s on K candidates of ``width`` features: the
    Dict of ``features`` and ``mask``, and ``failed`` in the retry setting (max_attempts > 1)."""
    from gymnasium import spaces

    if not isinstance(observation, spaces.Dict):
        return False
    keys = set(observation.spaces)
    return (keys in ({"features", "mask"}, {"features", "mask", "failed"})
            and tuple(observation["features"].shape) == (k, width)
            and all(tuple(observation[key].shape) == (k,) for key in keys - {"features"}))


def first_observation(found: CandidateSet, retry: bool) -> dict[str, np.ndarray]:
    """An episode's first ``GripSelect-v0`` observation of ``found`` (``failed`` all 0 when
    ``retry``: nothing tried yet)."""
    observation = {"features": found.features.copy(), "mask": found.mask.copy()}
    if retry:
        observation["failed"] = np.zeros_like(found.mask)
    return observation


def policy_scores(policy: Any, sets: Sequence[CandidateSet], seed: int, name: str,
                  spec: str) -> pd.DataFrame:  # fmt: skip
    """Score table of an observation policy: ``policy.predict(observation)`` on each object's
    first ``GripSelect-v0`` observation returns a slot (or SB3's ``(action, state)``), scored 1
    for that slot and 0 for the rest; a padded slot is refused."""
    check_policy_spaces(policy, sets, spec)
    retry = "failed" in getattr(getattr(policy, "observation_space", None), "spaces", {})
    frames = []
    for found in sets:
        observation = first_observation(found, retry)
        where = f"{spec}.predict on object {found.object_id!r}"
        try:
            action = policy.predict(observation)
        except Exception as exc:  # the user's code: its failure is bad input, in one line
            raise ValueError(f"{where} failed: {type(exc).__name__}: {exc}") from None
        if isinstance(action, tuple):  # SB3's (action, state)
            action = action[0]
        action = np.asarray(action).reshape(-1)[0] if np.size(action) == 1 else action
        scores = choice_scores(action, found.count, where)
        frames.append(score_frame(name, seed, _slots(found), scores))
    return pd.concat(frames, ignore_index=True)


# ------------------------------------------------------------------ d3rlpy policies
def load_d3rlpy(path: Path) -> Any:
    """A d3rlpy algorithm saved with ``save`` (a ``.d3`` file), on the CPU."""
    from classifiers.experiments.offline_rl import require_d3rlpy

    d3rlpy = require_d3rlpy()
    try:
        return d3rlpy.load_learnable(str(path), device="cpu:0")
    except (zipfile.BadZipFile, ValueError, KeyError, OSError, RuntimeError, TypeError,
            EOFError) as exc:  # fmt: skip
        reason = " ".join(str(exc).split())[:300]
        raise ValueError(f"{path} is not a d3rlpy policy file ({type(exc).__name__}: "
                         f"{reason})") from None  # fmt: skip


def check_d3rlpy_spaces(algo: Any, sets: Sequence[CandidateSet], path: Path) -> None:
    """ValueError unless the policy's observation and action sizes are this split's
    (flat observation ``K * F + K``, ``K`` discrete actions)."""
    k, width = sets[0].features.shape
    shape = tuple(getattr(algo.impl, "observation_shape", ()) or ())
    size = getattr(algo.impl, "action_size", None)
    if shape != (k * width + k,) or size != k:
        raise ValueError(f"{path}: observation shape {shape} / {size} actions do not match the "
                         f"split's GripSelect-v0 ({k * width + k},) flat observation "
                         f"(features {k}x{width} and mask {k}) and Discrete({k})")  # fmt: skip


def d3rlpy_scores(path: Path, sets: Sequence[CandidateSet], name: str) -> pd.DataFrame:
    """Score table of a d3rlpy policy: each real slot's Q-value on the object's observation
    (a Q-learning algorithm), or 1 for the slot it picks (behaviour cloning)."""
    from classifiers.experiments.offline_rl import flat_observation

    algo = load_d3rlpy(path)
    check_d3rlpy_spaces(algo, sets, path)
    counts = np.array([found.count for found in sets])
    flat = np.stack([flat_observation(found.features, found.mask) for found in sets])
    slots = np.concatenate([np.arange(c) for c in counts])
    try:
        values = algo.predict_value(np.repeat(flat, counts, axis=0), slots)
        per_object = np.split(np.asarray(values, dtype=float), np.cumsum(counts)[:-1])
    except NotImplementedError:  # behaviour cloning has no value function: its pick
        per_object = [int(a) for a in algo.predict(flat)]
    frames = [score_frame(name, 0, _slots(found), choice_scores(
        out, found.count, f"{path.name} on object {found.object_id!r}"))
        for found, out in zip(sets, per_object, strict=True)]  # fmt: skip
    return pd.concat(frames, ignore_index=True)


# ------------------------------------------------------------------ saved models
def saved_model_scores(path: Path, sets: Sequence[CandidateSet], name: str) -> pd.DataFrame:
    """Score table of a scikit-learn model (one run): a bare skops file, or any file of a model
    ``grip-env train`` saved (``NAME.json`` and its ``.skops``, ``.pt`` or ``.txt``)."""
    model = load_saved_model(path)
    frames = []
    for found in sets:
        rows = public_rows(found)
        features = getattr(model, "feature_names_in_", None)
        shown = rows if features is None else _columns(rows, list(features), path)
        scores = choice_scores(_model_scores(model, shown), found.count,
                               f"{path.name} on object {found.object_id!r}")  # fmt: skip
        frames.append(score_frame(name, 0, _slots(found), scores))
    return pd.concat(frames, ignore_index=True)


def load_saved_model(path: Path) -> Any:
    """The model of ``path``: through its ``NAME.json`` when it has one (as ``grip-env
    predict`` reads it), else a bare skops file."""
    from classifiers.learners.persistence import model_format

    meta = path.with_suffix(".json")
    if meta.is_file() and model_format(meta) is not None:
        return _load_with_metadata(path.parent, path.stem)
    if path.suffix.lower() == ".skops":
        return load_skops(path)
    raise ValueError(f"{path}: not a saved model (grip-env train writes OUT/models/NAME.json "
                     f"beside its .skops, .pt or .txt)")  # fmt: skip


def _load_with_metadata(directory: Path, name: str) -> Any:
    import json
    import pickle

    from classifiers.learners.persistence import load_model

    try:
        model, _ = load_model(directory, name)
    except (pickle.UnpicklingError, RuntimeError, KeyError, TypeError, OSError,
            zipfile.BadZipFile, json.JSONDecodeError) as exc:  # fmt: skip
        reason = " ".join(str(exc).split())[:300]
        raise ValueError(f"cannot load model {directory / name}: {type(exc).__name__}: "
                         f"{reason}") from None  # fmt: skip
    return model


def load_skops(path: Path) -> Any:
    """A skops model, trusting only scikit-learn's and this package's types."""
    import skops.io as sio

    from classifiers.learners.persistence import TRUSTED_PREFIXES, TRUSTED_TYPES

    try:
        untrusted = sio.get_untrusted_types(file=path)
    except (zipfile.BadZipFile, KeyError, OSError) as exc:
        raise ValueError(f"{path} is not a skops model file ({exc})") from None
    unexpected = sorted(t for t in untrusted
                        if t not in TRUSTED_TYPES and not t.startswith(TRUSTED_PREFIXES))
    if unexpected:
        raise ValueError(f"{path} holds types outside the trusted list: {unexpected}")
    model = sio.load(path, trusted=untrusted)
    if not any(hasattr(model, m) for m in ("decision_function", "predict_proba", "predict")):
        raise ValueError(f"{path} holds a {type(model).__name__}, not a fitted model")
    return model


def _model_scores(model: Any, rows: pd.DataFrame) -> np.ndarray:
    from classifiers.evaluation.cross_validation import ranking_score

    if hasattr(model, "classes_"):
        return ranking_score(model, rows)
    return np.asarray(model.predict(rows), dtype=float)


def _columns(rows: pd.DataFrame, names: list[str], path: Path) -> pd.DataFrame:
    missing = [n for n in names if n not in rows.columns]
    if missing:
        raise ValueError(f"{path} needs columns the candidate table lacks: {missing}")
    return rows[names]


# ------------------------------------------------------------------ SB3 policies
def load_sb3(path: Path) -> Any:
    """A MaskablePPO or PPO model from an SB3 zip (the algorithm read from its policy class)."""
    from sb3_contrib import MaskablePPO
    from sb3_contrib.common.maskable.policies import MaskableActorCriticPolicy
    from stable_baselines3 import PPO
    from stable_baselines3.common.save_util import load_from_zip_file

    import classifiers.experiments.selector.policy  # noqa: F401  (the selector's policy class, for unpickling)

    try:
        data, _, _ = load_from_zip_file(path, load_data=True, device="cpu")
    except (zipfile.BadZipFile, ValueError, KeyError, OSError) as exc:
        raise ValueError(f"{path} is not a Stable-Baselines3 zip ({exc})") from None
    policy_class = (data or {}).get("policy_class")
    if not isinstance(policy_class, type):
        raise ValueError(f"{path}: no policy class recorded (not an SB3 PPO/MaskablePPO zip)")
    algorithm = MaskablePPO if issubclass(policy_class, MaskableActorCriticPolicy) else PPO
    return algorithm.load(path, device="cpu")


def check_sb3_spaces(model: Any, sets: Sequence[CandidateSet], path: Path) -> None:
    """ValueError unless the model's spaces are ``GripSelect-v0``'s on this split."""
    from gymnasium import spaces

    k, width = sets[0].features.shape
    observation, action = model.observation_space, model.action_space
    expected = f"Dict(features=({k}, {width}), mask=({k},)[, failed=({k},)]) and Discrete({k})"
    ok = (select_observation_space(observation, k, width)
          and isinstance(action, spaces.Discrete) and int(action.n) == k)  # fmt: skip
    if not ok:
        raise ValueError(f"{path}: observation {observation} / action {action} do not match the "
                         f"split's GripSelect-v0 spaces {expected}")  # fmt: skip


def sb3_scores(path: Path, sets: Sequence[CandidateSet], seed: int, name: str) -> pd.DataFrame:
    """Score table of an SB3 policy: its action probabilities on each object's observation.

    A MaskablePPO policy of the retry setting (its observation has ``failed``) is scored by the
    slots it picks in turn, each pick's failure shown to it as the environment shows it
    (masked and marked failed): the k-th pick scores ``count - k``, so the table's order is
    the deterministic policy's own order after each failure, and the retry board scores what it
    does with a failure (its first pick is its most probable slot, as for any policy)."""
    import torch as th

    model = load_sb3(path)
    check_sb3_spaces(model, sets, path)
    from sb3_contrib.common.maskable.policies import MaskableActorCriticPolicy

    masked = isinstance(model.policy, MaskableActorCriticPolicy)
    if masked and "failed" in model.observation_space.spaces:
        return _adaptive_order_scores(model, sets, seed, name)
    frames = []
    with th.no_grad():
        for found in sets:
            observation = {"features": found.features[None], "mask": found.mask[None]}
            tensor, _ = model.policy.obs_to_tensor(observation)
            mask = {"action_masks": found.mask[None].copy()} if masked else {}
            distribution = model.policy.get_distribution(tensor, **mask)
            probability = distribution.distribution.probs.cpu().numpy()[0, : found.count]
            frames.append(score_frame(name, seed, _slots(found), probability))
    return pd.concat(frames, ignore_index=True)


def _adaptive_order_scores(model: Any, sets: Sequence[CandidateSet], seed: int,
                           name: str) -> pd.DataFrame:  # fmt: skip
    """Scores ``count - k`` for the k-th slot a retry policy picks, every failure shown."""
    from classifiers.experiments.selector.evaluation import order_scores, policy_orders

    orders = policy_orders(model, sets, max(found.count for found in sets))
    return pd.concat([score_frame(name, seed, _slots(found), order_scores(order, found.count))
                      for found, order in zip(sets, orders, strict=True)], ignore_index=True)


# ------------------------------------------------------------------ a study's score files
def study_scores(out: Path) -> pd.DataFrame | None:
    """The learners' per-seed score tables of a study folder (classifiers, rankers, RL)."""
    frames = [pd.read_parquet(out / f) for f in SCORE_FILES if (out / f).exists()]
    frames = [frame for frame in frames if len(frame)]
    if not frames:
        return None
    table = pd.concat(frames, ignore_index=True)
    missing = [c for c in SCORE_COLUMNS if c not in table.columns]
    if missing:
        raise ValueError(f"score files of {out} lack the columns {missing}")
    table["object_id"] = table["object_id"].astype(str)
    return drop_duplicates(table[list(SCORE_COLUMNS)])


def drop_duplicates(scores: pd.DataFrame) -> pd.DataFrame:
    """Scores without the learned copies of the baselines (:data:`DUPLICATES`)."""
    names = scores["method"].astype(str)
    return scores[~names.str.endswith(DUPLICATES).to_numpy()]


def fitted_scores(table: pd.DataFrame, candidates: pd.DataFrame, config: Any,
                  seeds: Sequence[int]) -> pd.DataFrame:  # fmt: skip
    """Each of ``learning.models`` and ``learning.regressors`` fitted on the training objects
    (everything but the held-out objects) with each seed, scoring the held-out candidates."""
    from classifiers.evaluation.cross_validation import LABEL_COLUMN
    from classifiers.evaluation.regression import TARGET_COLUMN, has_target
    from classifiers.learners.models import make_model, make_regressor
    from grip_env.columns import FEATURES

    train = table[~table["object_id"].astype(str).isin(set(candidates["object_id"]))]
    learning, frames = config.learning, []
    shown = candidates.drop(columns=hidden_columns(list(candidates.columns)))
    for seed in seeds:
        for name in learning.models:
            model = make_model(name, seed, FEATURES).fit(train, train[LABEL_COLUMN].astype(bool))
            frames.append(score_frame(f"classifier_{name}", seed, candidates,
                                      _model_scores(model, shown)))  # fmt: skip
        if has_target(train):
            for name in learning.regressors:
                model = make_regressor(name, seed, FEATURES).fit(train, train[TARGET_COLUMN])
                frames.append(score_frame(f"regressor_{name}", seed, candidates,
                                          model.predict(shown)))  # fmt: skip
    return drop_duplicates(pd.concat(frames, ignore_index=True))


def _slots(found: CandidateSet) -> pd.DataFrame:
    return pd.DataFrame({"object_id": found.object_id, "candidate": np.arange(found.count)})
