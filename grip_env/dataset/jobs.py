"""The per-object job: plan grips on an object, keep a sample of them, simulate and label them.

A job is a plain function ``job(task) -> DataFrame`` of dataset rows. It depends only on its task
(object, config, seed), so a dataset is the same whatever runs the jobs and in what order.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from grip_env.columns import (
    DATASET_COLUMNS,
    ROBUSTNESS,
    trial_robustness_columns,
    trial_success_columns,
)
from grip_env.config import Config
from grip_env.objects import PlanarObject

if TYPE_CHECKING:
    from grip_env.sim.world import World

#: ``success``: the grip held the reference disturbance in at least this share of its trials.
SUCCESS_THRESHOLD = 0.5


@dataclass(frozen=True, eq=False)
class ObjectTask:
    """Everything one object's job needs: the true object, the run config and its own seed."""

    index: int
    object_id: str
    obj: PlanarObject
    config: Config
    seed: int
    planned_on: PlanarObject | None = None
    """The contour the grips are planned on, when already perceived (see ``plans_on_render``)."""

    def child_seeds(self) -> tuple[int, int]:
        """Independent (perception, trials) seeds derived from the object's seed."""
        perception, trials = np.random.SeedSequence(self.seed).spawn(2)
        return int(perception.generate_state(1)[0]), int(trials.generate_state(1)[0])

    def sampling_seed(self) -> int:
        """Seed of the choice of kept grips, independent of the perception and trial seeds."""
        return int(np.random.SeedSequence(self.seed, spawn_key=(2,)).generate_state(1)[0])


ObjectJob = Callable[[ObjectTask], pd.DataFrame]


def object_seeds(run_seed: int, count: int) -> list[int]:
    """Seed of object ``i``: a function of (run seed, i) only, via ``numpy.random.SeedSequence``."""
    return [
        int(np.random.SeedSequence(run_seed, spawn_key=(index,)).generate_state(1)[0])
        for index in range(count)
    ]


def simulate_object(task: ObjectTask) -> pd.DataFrame:
    """The real job: candidates on the (perceived) contour, the ones ``dataset.sampling`` keeps,
    trials on the true contour.

    The trials' draws are keyed by the run seed and the object's id (common to its grips), never
    by the object's position in the run. Every trial's outcome is kept by trial index beside
    the summaries (:func:`~grip_env.columns.trial_columns`)."""
    from grip_env.sim import run_trial_outcomes
    from grip_env.sim.execution import trial_summary

    config = task.config
    kept = kept_grips(task)
    trials = config.dataset.trials
    outcome = run_trial_outcomes(task.obj, kept.assign(object_id=task.object_id), config,
                                 trials, config.dataset.seed)
    robust = outcome["robustness"].to_numpy(float).reshape(len(kept), trials)
    success = outcome["success"].to_numpy(bool).reshape(len(kept), trials)
    return with_outcomes(kept, trial_summary(robust, success), task.object_id,
                         (robust, success))


def kept_grips(task: ObjectTask) -> pd.DataFrame:
    """The candidates planned on the task's (perceived) contour, at the true body's height, that
    ``dataset.sampling`` keeps (seeded by the task's sampling seed)."""
    from grip_env.dataset.sampling import keep_grips

    table = _candidates_on(task, task.planned_on or planning_contour(task))
    return keep_grips(table, task.config.dataset, task.sampling_seed())


def planned_candidates(
    obj: PlanarObject, config: Config | None = None, *, perceive: bool | None = None,
    index: int = 0, world: World | None = None,
) -> tuple[PlanarObject, pd.DataFrame]:
    """Every candidate ``generate`` plans for ``obj`` as object ``index`` of a run (before
    ``dataset.sampling`` keeps some), and the object it plans them on.

    :func:`grip_env.pipeline.candidates` plans on the object it is given; ``generate`` plans on
    :func:`planned_object` (by default the contour segmented from a top-down render) at the true
    body's height. This is that plan; the arguments are :func:`planned_object`'s.

    Returns:
        The object planned on and its candidate table, best first by Q_C.
    """
    planned_on = planned_object(obj, config, perceive=perceive, index=index, world=world)
    return planned_on, _candidates_on(_run_task(obj, config, index), planned_on)


def planned_object(
    obj: PlanarObject, config: Config | None = None, *, perceive: bool | None = None,
    index: int = 0, world: World | None = None,
) -> PlanarObject:
    """The object ``generate`` plans the grips of ``obj`` on, as object ``index`` of a run.

    That is its contour segmented from a top-down render when ``plans_on_render(config)`` (the
    default, ``perception.source: render``), seeded by the object's seed (a function of
    ``config.dataset.seed`` and ``index`` only), else ``obj`` itself.

    Args:
        obj: the true object.
        config: the run's settings (defaults when None).
        perceive: the perceived contour (True) or ``obj``'s own (False); None: as ``generate``
            plans under ``config``.
        index: the object's position in the run (its seed, so its perceived contour).
        world: a simulation world to render in (one is opened when None).
    """
    task = _run_task(obj, config, index)
    perceive = plans_on_render(task.config) if perceive is None else perceive
    return perceived_contour(task, world) if perceive else obj


def _run_task(obj: PlanarObject, config: Config | None, index: int) -> ObjectTask:
    """The task of ``obj`` as object ``index`` of a run under ``config`` (defaults when None)."""
    if not isinstance(obj, PlanarObject):
        raise ValueError(f"obj must be a PlanarObject, got {type(obj).__name__}")
    if not isinstance(index, int) or isinstance(index, bool) or index < 0:
        raise ValueError(f"index must be an integer >= 0, got {index!r}")
    config = Config() if config is None else config
    seed = object_seeds(config.dataset.seed, index + 1)[index]
    return ObjectTask(index, obj.name, obj, config, seed)


def _candidates_on(task: ObjectTask, planned_on: PlanarObject) -> pd.DataFrame:
    """The candidates planned on ``planned_on`` at the height of the task's true body."""
    from grip_env.objects.meshes import execution_height_mm
    from grip_env.planning.pipeline import candidates

    config = task.config
    height = execution_height_mm(task.obj, config.objects)  # of the true body
    return candidates(planned_on, config.grasp, config, height_mm=height)


def plans_on_render(config: Config) -> bool:
    """Whether grips are planned on the contour segmented from the top-down render
    (``perception.source: render``, or the older ``uncertainty.perceived_contour``)."""
    return config.perception.source == "render" or config.uncertainty.perceived_contour


def planning_contour(task: ObjectTask, world: World | None = None) -> PlanarObject:
    """The object the task's grips are planned on: its rendered and segmented contour (seeded by
    the task's perception seed) when ``plans_on_render``, else the true object."""
    return perceived_contour(task, world) if plans_on_render(task.config) else task.obj


def perceived_contour(task: ObjectTask, world: World | None = None) -> PlanarObject:
    """The task's object as the camera sees it: rendered from above and segmented, seeded by the
    task's perception seed; ``world`` (optional) is reused for the rendering."""
    from grip_env.sim.camera import perceive

    config = task.config
    return perceive(task.obj, config.perception, config.objects.thickness_mm,
                    seed=task.child_seeds()[0], world=world)


def with_outcomes(
    grips: pd.DataFrame, outcome: pd.DataFrame | Mapping[str, ArrayLike], object_id: str,
    per_trial: tuple[ArrayLike, ArrayLike] | None = None,
) -> pd.DataFrame:
    """Dataset rows: candidates with the object's id, unique grip ids and the outcome columns.

    ``outcome`` holds ``trials``, ``successes``, ``robustness_mean`` and ``robustness_std`` per
    grip, in the order of ``grips`` (as :func:`grip_env.sim.run_trials` returns them);
    ``success_rate = successes / trials`` and ``success = success_rate >= 0.5``.
    ``grip_id`` becomes ``"<object_id>/<grip id within the object>"``, unique across a dataset
    (a leading ``"<candidate object_id>/"`` in the candidate's grip id is replaced).
    ``per_trial`` (robustness, success), each grips × trials by trial index, adds the columns
    ``trial_success_k`` and ``trial_robustness_k``; ``outcome`` must be their summary.
    """
    rows = grips.reset_index(drop=True).copy()
    local_ids = [
        str(grip).removeprefix(f"{owner}/")
        for owner, grip in zip(rows["object_id"], rows["grip_id"], strict=True)
    ]
    rows["object_id"] = object_id
    rows["grip_id"] = [f"{object_id}/{grip}" for grip in local_ids]
    for name in ("trials", "successes"):
        rows[name] = np.asarray(outcome[name], dtype=np.int64)
    with np.errstate(divide="ignore", invalid="ignore"):
        rows["success_rate"] = rows["successes"] / rows["trials"]
    rows["success"] = rows["success_rate"] >= SUCCESS_THRESHOLD
    for name in ROBUSTNESS:
        rows[name] = np.asarray(outcome[name], dtype=np.float64)
    rows = rows.loc[:, list(DATASET_COLUMNS)]
    if per_trial is None:
        return rows
    robust, success = (np.asarray(a) for a in per_trial)
    trials = robust.shape[1] if robust.ndim == 2 else 0
    if robust.shape != (len(rows), trials) or success.shape != robust.shape:
        raise ValueError(f"per-trial outcomes must be grips x trials, got {robust.shape} and "
                         f"{success.shape} for {len(rows)} grips")
    success_frame = pd.DataFrame(success.astype(bool), columns=list(trial_success_columns(trials)))
    robust_frame = pd.DataFrame(robust.astype(np.float64),
                                columns=list(trial_robustness_columns(trials)))
    return pd.concat([rows, success_frame, robust_frame], axis=1)
