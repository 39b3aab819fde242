"""What starts a held object moving through the ramp: each contact's load at every step (run by
hand; issue 45).

    python -m tests.benchmarks.ramp_contact_loads --family mesh --workers 2

The grips and trials of ``ramp_creep`` (trial 0 of the lowest and highest third by C1 of every
grip of the 80-object cross-check sample's ``--family``, both engines, every direction climbed
to its own failure). After every step of the ramp each hand-object contact pressed with at least
1 N is read as ``crosscheck_contact_loads`` reads it: its sideways load f_t / (mu N) in both
engines and, in MuJoCo, its twist load tau / (mu s N) and its load against the elliptic cone
(PyBullet does not report the spinning-friction torque). For the weakest direction's climb it
reports, over the steps of the levels held and over the steps of the level that failed: the share
of steps with some contact at its bound (MuJoCo's ellipse, PyBullet's sideways box, at 0.98), at
the bound by sliding alone (sideways load >= 0.98), and, in MuJoCo, at the ellipse with both
its sideways and its twist load below 0.9 of their own bounds (a load a box would still carry);
the twist's share of the most loaded contact's ellipse (twist^2 / (side^2 + twist^2)); the share
of steps with a link other than a fingertip's loaded; the loaded contacts a step; and the share of
steps with a fingertip touching through more than one loaded contact, and of steps with a link
pressing through two loaded contacts at one spot (within 2 mm: two convex pieces at a seam, or
PyBullet's manifold keeping an earlier point) and at two spots further apart.
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import functools
from typing import Any

import numpy as np
import pandas as pd

from tests.benchmarks.crosscheck_contact_loads import (
    MIN_NORMAL_N,
    loads,
    mujoco_contacts,
    mujoco_hand_contacts,
    pybullet_contacts,
)
from tests.benchmarks.hold_squeeze import family_table
from tests.benchmarks.ramp_creep import _Recorder, run_object, weakest_climb

AT_BOUND = 0.98
BELOW = 0.9
STEP_COLUMNS = ["climb", "level", "drift", "turn", "give", "travel", "bound", "slide", "combined",
                "twist_share", "other_link", "contacts", "shared_tip", "stacked", "apart"]
SAME_SPOT_MM = 2.0  # two contacts of one link nearer than this press one patch of it


class _LoadRecorder(_Recorder):
    """``ramp_creep``'s recorder, with the contacts' loads after every step."""

    def step(self) -> None:
        from grip_env.sim.hand import FINGER_LINKS

        super().step()
        mujoco = self.scene.config.sim.engine == "mujoco"
        table = loads((mujoco_contacts if mujoco else pybullet_contacts)(self.scene))
        tips = {links[-1] for links in FINGER_LINKS}
        spots = _spots(self.scene, mujoco)
        self.rows[-1] = (*self.rows[-1], *_step_loads(table, tips, mujoco), *_spread(spots))


def _spots(scene: Any, mujoco: bool) -> list[tuple[int, np.ndarray]]:
    """(hand link, world position in mm) of each hand-object contact pressed with at least
    ``MIN_NORMAL_N``."""
    world, hand, obj = scene.world, scene.hand.uid, scene.object.uid
    if not mujoco:
        return [(int(p[3]), 1e3 * np.array(p[6])) for p in
                world.client.getContactPoints(bodyA=hand, bodyB=obj) if p[9] >= MIN_NORMAL_N]
    return [(hand_link, 1e3 * np.array(c.pos)) for c, hand_link, wrench in
            mujoco_hand_contacts(scene) if wrench[0] >= MIN_NORMAL_N]


def _spread(spots: list[tuple[int, np.ndarray]]) -> tuple[float, float]:
    """Whether some link presses through two loaded contacts at one spot (stacked: nearer than
    ``SAME_SPOT_MM``), and whether some link presses at two spots (apart)."""
    stacked = apart = False
    for k, (link, at) in enumerate(spots):
        for other, there in spots[k + 1:]:
            if other == link:
                near = float(np.linalg.norm(at - there)) < SAME_SPOT_MM
                stacked, apart = stacked or near, apart or not near
    return float(stacked), float(apart)


def _step_loads(table: np.ndarray, tips: set[int], mujoco: bool) -> tuple[float, ...]:
    """(at the bound, sliding, combined, the twist's share, another link loaded) of one step's
    contact loads (rows of ``crosscheck_contact_loads.loads``)."""
    if not len(table):
        return (0.0, 0.0, 0.0, np.nan, 0.0, 0.0, 0.0)
    side, twist, ellipse = table[:, 2], table[:, 3], table[:, 4]
    level = ellipse if mujoco else side
    top = int(np.argmax(level))
    bound = level >= AT_BOUND
    combined = bound & (side < BELOW) & (twist < BELOW) if mujoco else np.zeros_like(bound)
    share = twist[top] ** 2 / max(side[top] ** 2 + twist[top] ** 2, 1e-12) if mujoco else np.nan
    links = table[:, 0].astype(int).tolist()
    other = any(link not in tips for link in links)
    shared = any(links.count(tip) > 1 for tip in tips)
    return (float(bound.any()), float((side >= AT_BOUND).any()), float(combined.any()),
            float(share), float(other), float(len(links)), float(shared))


def _loads_summary(recorder: _Recorder, sim: Any) -> dict[str, float]:
    """The weakest climb's contact loads, over its held levels and over its failing level."""
    table = pd.DataFrame(recorder.rows, columns=STEP_COLUMNS)
    climb, first_bad = weakest_climb(table, sim)
    rows = table[table.climb == climb]
    parts = {"held": rows[rows.level < first_bad], "failing": rows[rows.level == first_bad]}
    out: dict[str, float] = {"direction": climb, "broke": float(np.isfinite(first_bad))}
    for name, part in parts.items():
        for column in STEP_COLUMNS[6:]:
            out[f"{name}_{column}"] = float(part[column].mean()) if len(part) else np.nan
    return out


def main() -> None:
    run = functools.partial(run_object, recorder=_LoadRecorder, summarize=_loads_summary)
    table, family = family_table(__doc__, run)
    columns = [c for c in table.columns if c.startswith(("held_", "failing_"))]
    with pd.option_context("display.width", 250, "display.max_columns", 30):
        print(f"{table.object_id.nunique()} {family} objects, held trials by engine: the share "
              "of the weakest climb's steps")
        for part in ("held", "failing"):
            cols = [c for c in columns if c.startswith(part)]
            print(table.groupby(["C1 third", "engine"], observed=True)[
                ["robustness", *cols]].mean().round(3).to_string())
        print(table.groupby(["C1 third", "engine"], observed=True).size().to_string())


if __name__ == "__main__":
    main()
