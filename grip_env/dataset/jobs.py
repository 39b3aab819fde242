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

from grip_env.columns import DATASET_COLUMNS, ROBUSTNESS
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
    by the object's position in the run."""
    from grip_env.sim import run_trials

    config = task.config
    kept = kept_grips(task)
    outcome = run_trials(task.obj, kept.assign(object_id=task.object_id), config,
                         config.dataset.trials, config.dataset.seed)
    return with_outcomes(kept, outcome, task.object_id)


def kept_grips(task: ObjectTask) -> pd.DataFrame:
    """The candidates planned on the task's (perceived) contour, at the true body's height, that
    ``dataset.sampling`` keeps (seeded by the task's sampling seed)."""
    from grip_env.dataset.sampling import keep_grips
    from grip_env.objects.meshes import execution_height_mm
    from grip_env.planning.pipeline import candidates

    config = task.config
    planned_on = task.planned_on or planning_contour(task)
    height = execution_height_mm(task.obj, config.objects)  # of the true body
    table = candidates(planned_on, config.grasp, config, height_mm=height)
    return keep_grips(table, config.dataset, task.sampling_seed())


def plans_on_render(config: Config) -> bool:
    """Whether grips are planned on the contour segmented from the top-down render
    (``perception.source: render``, or the older ``uncertainty.perceived_contour``)."""
    return config.perception.source == "render" or config.uncertainty.perceived_contour


def planning_contour(task: ObjectTask, world: World | None = None) -> PlanarObject:
    """The object the task's grips are planned on: its rendered and segmented contour (seeded by
    the task's perception seed) when ``plans_on_render``, else the true object."""
    if not plans_on_render(task.config):
        return task.obj
    from grip_env.sim.camera import perceive

    config = task.config
    return perceive(task.obj, config.perception, config.objects.thickness_mm,
                    seed=task.child_seeds()[0], world=world)


def with_outcomes(
    grips: pd.DataFrame, outcome: pd.DataFrame | Mapping[str, ArrayLike], object_id: str
) -> pd.DataFrame:
    """Dataset rows: candidates with the object's id, unique grip ids and the outcome columns.

    ``outcome`` holds ``trials``, ``successes``, ``robustness_mean`` and ``robustness_std`` per
    grip, in the order of ``grips`` (as :func:`grip_env.sim.run_trials` returns them);
    ``success_rate = successes / trials`` and ``success = success_rate >= 0.5``.
    ``grip_id`` becomes ``"<object_id>/<grip id within the object>"``, unique across a dataset
    (a leading ``"<candidate object_id>/"`` in the candidate's grip id is replaced).
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
    return rows.loc[:, list(DATASET_COLUMNS)]
