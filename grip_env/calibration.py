"""Label validity: do the simulated outcomes measure the grip rather than the trial's draws?

``calibrate(config, settings)`` runs five measured checks through the public simulation API
(:func:`grip_env.sim.run_trial_outcomes`), one job per object on ``dataset.backend``
(:func:`grip_env.dataset.backends.run_jobs`):

- ``design_hold``: with no pose error, friction at the design value ``grasp.mu`` and the nominal
  mass, the best-Q_C grip of 90×55, 70×70 and 120×40 mm boxes holds the reference level;
- ``cone``: at friction ``grasp.mu`` (pose and mass noise as configured), the best grip whose
  finger force leaves the friction cone (C1's k = 3) against the best grip inside the cone, on
  default then procedural objects that have both, paired by object: mean robustness
  difference with a t-interval over objects;
- ``retest``: per-grip mean robustness from two disjoint sets of trial seeds (trials
  ``0..n-1`` and ``n..2n-1`` of one call, i.e. ``trial_offset = 0`` and ``n``) over the best and
  worst grips by Q_C of default objects: Spearman with a bootstrap interval over grips;
- ``icc``: ICC(1) of per-trial robustness with the grip as class (one-way random effects,
  Shrout & Fleiss 1979), with its exact F-based 95% interval;
- ``within_object``: within one object, do two sets of trials rank its grips alike (what a robot
  choosing among them needs)? On default then procedural objects, all the grips a dataset keeps
  for each (``dataset.sampling``) run 2n trials, n = ``dataset.trials`` (one common draw per
  trial and object); per object, Spearman of set-A (trials ``0..n-1``) against set-B
  (``n..2n-1``) grip means; their mean with a bootstrap interval over objects.

:func:`decile_check` adds the dataset check (Spearman of Q_C or Q_G decile against the decile's
mean robustness, with an object-cluster bootstrap interval). Every figure is reported as measured;
each check states its target and whether it passes.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from grip_env.config import Config
from grip_env.label_model import label_model_for
from grip_env.objects import PlanarObject, load_object_set, procedural_objects
from grip_env.objects.shapes import rectangle
from grip_env.progress import progress_bar

BOXES_MM: tuple[tuple[float, float], ...] = ((90.0, 55.0), (70.0, 70.0), (120.0, 40.0))
RETEST_TARGET = 0.8
#: Objects the within-object check must score (not tied on a side) for a verdict.
WITHIN_SCORED = 12
#: Kept grips an object needs to take part in the within-object check.
MIN_WITHIN_GRIPS = 4
ICC_TARGET = 0.5
DECILE_TARGET = -0.8
#: Procedural candidates per wanted cone object (nearly every procedural shape has grips both
#: in and out of the cone; the spare covers the ones that do not).
PROCEDURAL_SPARE = 2
TRIAL_COLUMNS = ("object_id", "grip", "part", "end", "Q_C", "Q_G", "trial", "robustness",
                 "success", "friction", "mass_kg")  # fmt: skip


@dataclass(frozen=True)
class CalibrationSettings:
    """Sizes of the calibration runs (``quick()`` shrinks them to seconds, for tests)."""

    retest_objects: int = 6  # default objects, in set order, with >= 2 * grips_per_end grips
    grips_per_end: int = 8  # best and worst grips by Q_C per object
    trials_per_set: int = 8  # trials in each of the two disjoint seed sets
    # default, then procedural, objects with grips in and out of the cone, and trials per grip:
    # chosen by measurement (BENCHMARKS, "cone check's power"): the spread of the per-object
    # difference is between objects (sd 37 g at 2 trials, 33 g at 4; 31 and 30 g at 4 and 8
    # before the worm-gear floor), so objects narrow the interval and trials hardly do; 40
    # objects give a half-width of 10-12 g, under half the effect
    cone_objects: int = 40
    cone_trials: int = 4
    design_trials: int = 2
    # default, then procedural, objects with >= MIN_WITHIN_GRIPS kept grips (0: no check), and
    # kept grips used per object (0: all of them, as the target asks; quick() caps them); 14 so
    # that WITHIN_SCORED are scored when a light box's grips all tie (every trial at the ceiling)
    within_objects: int = 14
    within_grips: int = 0
    bootstrap: int = 2000
    seed: int = 0
    workers: int = 2

    def __post_init__(self) -> None:
        for name, value in asdict(self).items():
            minimum = 0 if name in ("seed", "retest_objects", "cone_objects", "within_objects",
                                    "within_grips") else 1  # fmt: skip
            if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
                raise ValueError(f"calibration setting {name} must be an integer >= {minimum}, "
                                 f"got {value!r}")  # fmt: skip
        if 0 < self.within_grips < MIN_WITHIN_GRIPS:
            raise ValueError(f"calibration setting within_grips must be 0 (all) or >= "
                             f"{MIN_WITHIN_GRIPS}, got {self.within_grips}")  # fmt: skip

    @classmethod
    def quick(cls, workers: int = 1) -> CalibrationSettings:
        """A run of a few dozen trials: every check computed, none meaningful."""
        # three within-object objects: the first two, a rectangle and a square, have grips that
        # meet each common draw alike (a constant side: skipped)
        return cls(retest_objects=2, grips_per_end=2, trials_per_set=2, cone_objects=1,
                   cone_trials=2, design_trials=1, within_objects=3,
                   within_grips=MIN_WITHIN_GRIPS, bootstrap=200, workers=workers)  # fmt: skip


# ------------------------------------------------------------------------------------ objects
def box_objects() -> list[PlanarObject]:
    """The three calibration boxes (their thickness and density come from the config)."""
    return [
        PlanarObject.from_polygon(rectangle(w, h), name=f"box_{w:.0f}x{h:.0f}").centred()
        for w, h in BOXES_MM
    ]


def outside_cone(grips: pd.DataFrame, mu: float) -> np.ndarray:
    """True where some finger force F_i leaves the friction cone about N_i (C1's k = 3)."""
    limit = np.arctan(mu)
    outside = np.zeros(len(grips), dtype=bool)
    for i in "123":
        f = grips[[f"f{i}_x", f"f{i}_y"]].to_numpy(float)
        n = grips[[f"n{i}_x", f"n{i}_y"]].to_numpy(float)
        cosine = np.sum(f * n, axis=1) / (np.linalg.norm(f, axis=1) * np.linalg.norm(n, axis=1))
        outside |= np.arccos(np.clip(cosine, -1.0, 1.0)) > limit
    return outside


def design_config(config: Config) -> Config:
    """``config`` with no pose error, friction fixed at ``grasp.mu`` and no mass spread."""
    return fixed_friction_config(config).override(
        uncertainty={"position_std_mm": 0.0, "yaw_std_rad": 0.0, "mass_rel_std": 0.0}
    )


def fixed_friction_config(config: Config) -> Config:
    """``config`` with every trial's friction at the design value ``grasp.mu``."""
    mu = float(config.grasp.mu)
    return config.override(uncertainty={"friction_range": (mu, mu)})


def _planned(obj: PlanarObject, config: Config) -> pd.DataFrame:
    from grip_env.planning.pipeline import candidates

    table = candidates(obj, config.grasp, config)
    table = table[np.isfinite(table["Q_C"].to_numpy(float))]
    return table.sort_values("Q_C", kind="stable").set_index("grip_id", drop=False)


def kept_grips(obj: PlanarObject, table: pd.DataFrame, config: Config, seed: int,
               index: int) -> pd.DataFrame:
    """The grips of ``table`` a dataset keeps (``dataset.sampling``), with the sampling seed a
    dataset of run seed ``seed`` gives its object ``index`` (``ObjectTask.sampling_seed``)."""
    from grip_env.dataset.jobs import ObjectTask, object_seeds
    from grip_env.dataset.sampling import keep_grips

    task = ObjectTask(index, obj.name, obj, config, object_seeds(seed, index + 1)[index])
    return keep_grips(table, config.dataset, task.sampling_seed())


def spread_subset(grips: pd.DataFrame, count: int) -> pd.DataFrame:
    """``count`` rows spread evenly over ``grips``' order (all of them for ``count`` 0)."""
    if count == 0 or count >= len(grips):
        return grips
    return grips.iloc[np.unique(np.linspace(0, len(grips) - 1, count).round().astype(int))]


def _selections(obj: PlanarObject, config: Config, parts: Iterable[str],
                settings: CalibrationSettings,
                index: int = 0) -> list[tuple[str, str, pd.DataFrame, Config]]:
    """(part, end, grips, config) of each simulation the object (candidate ``index``) takes
    part in."""
    table = _planned(obj, config)
    runs = []
    if "design" in parts and len(table):
        runs.append(("design", "best", table.head(1), design_config(config)))
    if "cone" in parts:
        outside = table[outside_cone(table, config.grasp.mu)]
        inside = table[~outside_cone(table, config.grasp.mu)]
        if len(outside) and len(inside):
            fixed = fixed_friction_config(config)
            runs += [("cone", "best", inside.head(1), fixed),
                     ("cone", "outside", outside.head(1), fixed)]  # fmt: skip
    if "retest" in parts:
        n = settings.grips_per_end
        runs += [("retest", "best", table.head(n), config),
                 ("retest", "worst", table.tail(n), config)]  # fmt: skip
    if "within_object" in parts:
        kept = kept_grips(obj, table, config, settings.seed, index)
        runs.append(("within_object", "kept", spread_subset(kept, settings.within_grips), config))
    return runs


def _trials_for(part: str, settings: CalibrationSettings, config: Config) -> int:
    return {"design": settings.design_trials, "cone": settings.cone_trials,
            "retest": 2 * settings.trials_per_set,
            "within_object": 2 * config.dataset.trials}[part]  # fmt: skip


def object_job(task: Any, parts: dict[str, tuple[str, ...]],
               settings: CalibrationSettings) -> pd.DataFrame:
    """One object's calibration trials (long table, :data:`TRIAL_COLUMNS`); ``task.index`` is
    the object's position in :func:`candidate_objects`."""
    from grip_env.sim import run_trial_outcomes

    frames = []
    for part, end, grips, config in _selections(task.obj, task.config, parts[task.object_id],
                                                settings, task.index):
        outcomes = run_trial_outcomes(task.obj, grips.assign(object_id=task.object_id), config,
                                      trials=_trials_for(part, settings, config),
                                      seed=settings.seed)  # fmt: skip
        quality = grips.loc[outcomes["grip"], ["Q_C", "Q_G"]].to_numpy(float)
        frames.append(outcomes.assign(object_id=task.object_id, part=part, end=end,
                                      Q_C=quality[:, 0], Q_G=quality[:, 1]))  # fmt: skip
    if not frames:
        return pd.DataFrame(columns=list(TRIAL_COLUMNS))
    return pd.concat(frames, ignore_index=True).loc[:, list(TRIAL_COLUMNS)]


def candidate_objects(config: Config, settings: CalibrationSettings | None = None,
                      ) -> list[PlanarObject]:
    """The boxes, the default objects, then procedural objects: the study's, continued with the
    same seed (object ``i`` depends only on the seed and ``i``) so that the cone check finds
    ``settings.cone_objects`` (and ``within_objects``) objects even on a config with few
    procedural ones."""
    settings = settings or CalibrationSettings()
    count = max(config.objects.procedural_count, PROCEDURAL_SPARE * settings.cone_objects,
                settings.within_objects)  # fmt: skip
    procedural = procedural_objects(count, config.dataset.seed,
                                    config.objects.procedural_size_mm)  # fmt: skip
    return [*box_objects(), *load_object_set("default"), *procedural]


def choose_objects(config: Config, settings: CalibrationSettings) -> dict[str, tuple[str, ...]]:
    """Object name → calibration parts: the boxes (design); default objects in set order for
    the retest; default, then procedural, objects with grips in and out of the cone, and with
    at least :data:`MIN_WITHIN_GRIPS` kept grips (within-object)."""
    plan: dict[str, tuple[str, ...]] = {obj.name: ("design",) for obj in box_objects()}
    retest = cone = within = 0
    default = {obj.name for obj in load_object_set("default")}
    for index, obj in enumerate(candidate_objects(config, settings)):
        if index < len(BOXES_MM):
            continue
        if (retest >= settings.retest_objects and cone >= settings.cone_objects
                and within >= settings.within_objects):  # fmt: skip
            break
        table = _planned(obj, config)
        parts = []
        if (obj.name in default and retest < settings.retest_objects
                and len(table) >= 2 * settings.grips_per_end):  # fmt: skip
            parts.append("retest")
            retest += 1
        outside = outside_cone(table, config.grasp.mu)
        if cone < settings.cone_objects and outside.any() and not outside.all():
            parts.append("cone")
            cone += 1
        if (within < settings.within_objects and len(
                kept_grips(obj, table, config, settings.seed, index)) >= MIN_WITHIN_GRIPS):
            parts.append("within_object")
            within += 1
        if parts:
            plan[obj.name] = tuple(parts)
    return plan


def run_calibration_trials(
    config: Config, settings: CalibrationSettings,
    log: Callable[[str], None] = lambda message: None,
) -> pd.DataFrame:
    """Every calibration trial, one job per object on the config's backend (``dataset.backend``:
    a local process pool, or Ray, which joins the cluster ``$RAY_ADDRESS`` names)."""
    from grip_env.dataset.backends import run_jobs
    from grip_env.dataset.jobs import ObjectTask

    plan = choose_objects(config, settings)
    shapes = candidate_objects(config, settings)
    position = {obj.name: i for i, obj in enumerate(shapes)}
    tasks = [ObjectTask(position[name], name, shapes[position[name]], config, settings.seed)
             for name in plan]  # fmt: skip
    job = functools.partial(object_job, parts=plan, settings=settings)
    frames: dict[int, pd.DataFrame] = {}
    with progress_bar(len(tasks), "calibrate") as bar:
        workers = min(settings.workers, max(len(tasks), 1))
        for task, rows in run_jobs(job, tasks, workers, config.dataset.backend):
            log(f"[calibrate] {task.object_id}: {len(rows)} trials "
                f"({', '.join(plan[task.object_id])})")
            frames[task.index] = rows
            bar.advance(info=task.object_id)
    if not frames:
        return pd.DataFrame(columns=TRIAL_COLUMNS)
    # in the plan's order, not the workers' completion order: the same table whatever the workers
    return pd.concat([frames[task.index] for task in tasks if task.index in frames],
                     ignore_index=True)


# --------------------------------------------------------------------------------- statistics
def spearman_bootstrap(a: np.ndarray, b: np.ndarray, resamples: int = 2000,
                       seed: int = 0) -> dict[str, Any]:
    """Spearman of paired values with a percentile bootstrap 95% interval (resampling pairs)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.size < 3:
        return {"value": None, "ci": [None, None], "n": int(a.size)}
    value = _spearman(a, b)
    rng = np.random.default_rng(seed)
    draws = rng.integers(0, a.size, size=(resamples, a.size))
    boot = np.array([_spearman(a[d], b[d]) for d in draws])
    boot = boot[np.isfinite(boot)]
    ci = np.percentile(boot, [2.5, 97.5]).tolist() if boot.size else [None, None]
    return {"value": value, "ci": ci, "n": int(a.size)}


def mean_bootstrap(values: np.ndarray, resamples: int = 2000,
                   seed: int = 0) -> list[float | None]:
    """Percentile bootstrap 95% interval of the mean of independent values."""
    values = np.asarray(values, float)
    if values.size == 0:
        return [None, None]
    draws = np.random.default_rng(seed).integers(0, values.size, size=(resamples, values.size))
    return [float(c) for c in np.percentile(values[draws].mean(axis=1), [2.5, 97.5])]


def icc1(values: np.ndarray) -> dict[str, Any]:
    """ICC(1) of a (classes, k) table, with the exact 95% interval from the F distribution."""
    values = np.asarray(values, float)
    n, k = values.shape
    if n < 2 or k < 2:
        raise ValueError(f"ICC(1) needs >= 2 classes and >= 2 trials each, got {n}x{k}")
    grand = values.mean()
    msb = k * np.sum((values.mean(axis=1) - grand) ** 2) / (n - 1)
    msw = np.sum((values - values.mean(axis=1, keepdims=True)) ** 2) / (n * (k - 1))
    df1, df2 = n - 1, n * (k - 1)
    if msw == 0:
        return {"value": 1.0 if msb > 0 else None, "ci": [None, None], "n": n, "k": k}
    f = msb / msw
    low = f / stats.f.ppf(0.975, df1, df2)
    high = f * stats.f.ppf(0.975, df2, df1)
    value = (f - 1.0) / (f + k - 1.0)
    ci = [(low - 1.0) / (low + k - 1.0), (high - 1.0) / (high + k - 1.0)]
    return {"value": float(value), "ci": [float(c) for c in ci], "n": n, "k": k}


def t_interval(values: np.ndarray) -> dict[str, Any]:
    """Mean and 95% t-interval of independent values."""
    values = np.asarray(values, float)
    if values.size == 0:
        return {"mean": None, "ci": [None, None], "n": 0}
    mean = float(values.mean())
    if values.size == 1:
        return {"mean": mean, "ci": [mean, mean], "n": 1}
    half = stats.t.ppf(0.975, values.size - 1) * values.std(ddof=1) / np.sqrt(values.size)
    return {"mean": mean, "ci": [float(mean - half), float(mean + half)], "n": int(values.size)}


def _spearman(a: np.ndarray, b: np.ndarray) -> float:
    if np.unique(a).size < 2 or np.unique(b).size < 2:
        return float("nan")
    return float(stats.spearmanr(a, b).statistic)


# ------------------------------------------------------------------------------------- checks
def _check(name: str, measured: Any, ci: Any, target: str, passed: bool | None,
           **extra: Any) -> dict[str, Any]:
    return {"name": name, "measured": measured, "ci": ci, "target": target,
            "passed": passed, **extra}  # fmt: skip


def friction_ceiling_g(obj: PlanarObject, config: Config, normal_n: float | None = None) -> float:
    """The in-plane level (g) the pads hold by friction alone at the design value ``grasp.mu``.

    A level of ``a`` g pushes the object along the pads' faces with ``m a g`` while gravity pulls
    it down with ``m g``; only friction resists both, at most ``mu * normal_n``, so
    ``a <= sqrt((mu normal_n / (m g))**2 - 1)`` (0 when the pads cannot carry the weight).
    ``normal_n`` defaults to the commanded squeeze, ``3 * finger_force_n``: the ceiling of a hand
    whose normal forces stay at it. A non-backdrivable worm gear lets them rise under load
    (:func:`gear_ceiling_g`), so a measured level may sit above this one.
    """
    from grip_env.sim.uncertainty import object_mass_kg

    normal_n = 3 * config.sim.finger_force_n if normal_n is None else normal_n
    ratio = config.grasp.mu * normal_n / (object_mass_kg(obj, config) * 9.81)
    return float(np.sqrt(max(ratio**2 - 1.0, 0.0)))


def gear_ceiling_g(obj: PlanarObject, config: Config, hold_factor: float | None = None) -> float:
    """:func:`friction_ceiling_g` with every pad at the most its finger resists before it is
    pushed back: the motor's force plus the worm gear's stop, ``(1 + hold_factor)`` times it
    (an estimate: the stop is a joint torque, taken as the same multiple of the pad force).
    ``hold_factor`` defaults to the hand's ``HOLD_FACTOR``; a stop that holds any load
    (infinite) has no ceiling: ``inf``."""
    from grip_env.sim.hand import HOLD_FACTOR

    factor = HOLD_FACTOR if hold_factor is None else hold_factor
    if np.isinf(factor):
        return float("inf")
    return friction_ceiling_g(obj, config, 3 * (1 + factor) * config.sim.finger_force_n)


def friction_for_level(obj: PlanarObject, config: Config, level_g: float) -> float:
    """The pad friction coefficient whose :func:`friction_ceiling_g` (commanded squeeze) is
    ``level_g``."""
    from grip_env.sim.uncertainty import object_mass_kg

    weight_n = object_mass_kg(obj, config) * 9.81
    return float(np.hypot(level_g, 1.0) * weight_n / (3 * config.sim.finger_force_n))


def design_check(trials: pd.DataFrame, reference_g: float,
                 config: Config | None = None) -> dict[str, Any]:
    """Each box's best grip at the design friction: robustness, whether it holds, the box's
    friction ceilings (commanded squeeze, and with the worm gear's stop) and the friction the
    reference needs at the commanded squeeze.

    ``well_posed`` is False when the reference is above every box's gear ceiling: then no
    faithful grip can pass, and ``reason`` says why (the figure is reported, nothing is tuned).
    ``beyond_squeeze`` is True when the reference is above what the commanded squeeze alone
    holds at ``grasp.mu``: passing then relies on normal forces above it, which the worm gear
    allows (it keeps the squeeze reached and resists being pushed back).
    """
    config = config or Config()
    rows = trials[trials["part"] == "design"]
    per_box = rows.groupby("object_id").agg(grip=("grip", "first"), Q_C=("Q_C", "first"),
                                            robustness=("robustness", "mean"),
                                            held=("success", "mean"))  # fmt: skip
    boxes = {box.name: box for box in box_objects()}
    squeeze = {name: friction_ceiling_g(box, config) for name, box in boxes.items()}
    gear = {name: gear_ceiling_g(box, config) for name, box in boxes.items()}
    needed = {name: friction_for_level(box, config, reference_g) for name, box in boxes.items()}
    for column, values, digits in (("friction_ceiling_g", squeeze, 2), ("gear_ceiling_g", gear, 1),
                                   ("mu_for_reference", needed, 3)):  # fmt: skip
        per_box[column] = [_finite(round(values.get(n, np.nan), digits)) for n in per_box.index]
    passed = bool(len(per_box) == len(BOXES_MM) and (per_box["held"] == 1.0).all())
    well_posed = bool(max(gear.values()) >= reference_g)
    mu, force = config.grasp.mu, config.sim.finger_force_n
    reason = None if well_posed else (
        f"ill-posed at mu = {mu:g}: even with the worm gear's stop the pads hold these boxes by "
        f"friction against at most {min(gear.values()):.1f}–{max(gear.values()):.1f} g in the "
        f"plane, below the {reference_g:g} g reference")
    return _check("design_hold", per_box["robustness"].round(3).to_dict(), None,
                  f"every box's best-Q_C grip holds {reference_g:g} g", passed,
                  per_object=per_box.reset_index().to_dict(orient="records"),
                  well_posed=well_posed, reason=reason,
                  beyond_squeeze=bool(min(squeeze.values()) < reference_g),
                  squeeze_text=(f"three {force:g} N pads squeezing at mu = {mu:g} hold "
                                f"{min(squeeze.values()):.1f}–{max(squeeze.values()):.1f} g by "
                                f"friction (mu x sum N against the weight and the ramp's push); "
                                f"{reference_g:g} g at that squeeze needs mu >= "
                                f"{min(needed.values()):.2f}–{max(needed.values()):.2f}"))


def _finite(value: float) -> float | None:
    """``value``, or None for an infinite one (a ceiling the gear does not have; the JSON stays
    strict)."""
    return None if np.isinf(value) else value


def cone_check(trials: pd.DataFrame) -> dict[str, Any]:
    """Outside-cone grip minus best grip, mean robustness, paired by object."""
    rows = trials[trials["part"] == "cone"]
    means = rows.groupby(["object_id", "end"])["robustness"].mean().unstack("end")
    held = rows.groupby(["object_id", "end"])["success"].mean().unstack("end")
    if means.empty or not {"best", "outside"} <= set(means.columns):
        return _check("cone", None, [None, None], "difference < 0 with its interval", None)
    difference = t_interval((means["outside"] - means["best"]).to_numpy())
    passed = difference["ci"][1] is not None and difference["ci"][1] < 0 and difference["n"] > 1
    per_object = pd.DataFrame({"best_g": means["best"], "outside_g": means["outside"],
                               "best_held": held["best"], "outside_held": held["outside"]})
    low, high = difference["ci"]
    return _check("cone", difference["mean"], difference["ci"],
                  "outside-cone minus best < 0, 95% interval below 0", bool(passed),
                  half_width=None if low is None else (high - low) / 2,
                  per_object=per_object.reset_index().to_dict(orient="records"))


def retest_table(trials: pd.DataFrame, trials_per_set: int, part: str = "retest",
                 ) -> pd.DataFrame:
    """Per grip of ``part``: mean robustness on seed set A (first n trials) and set B (next n)."""
    rows = trials[trials["part"] == part].assign(
        seed_set=lambda t: np.where(t["trial"] < trials_per_set, "A", "B")
    )
    table = rows.pivot_table(index=["object_id", "grip", "end", "Q_C"], columns="seed_set",
                             values="robustness", aggfunc="mean")  # fmt: skip
    return table.reset_index().rename_axis(columns=None)


def retest_check(trials: pd.DataFrame, settings: CalibrationSettings) -> dict[str, Any]:
    """Spearman of set-A against set-B grip means, pooled (bootstrap) and within objects."""
    table = retest_table(trials, settings.trials_per_set)
    if not {"A", "B"} <= set(table.columns):
        return _check("retest", None, [None, None], f"Spearman >= {RETEST_TARGET}", None)
    pooled = spearman_bootstrap(table["A"], table["B"], settings.bootstrap, settings.seed)
    within = np.array([_spearman(g["A"].to_numpy(), g["B"].to_numpy())
                       for _, g in table.groupby("object_id")])
    ranked = within[np.isfinite(within)]  # an object with a constant side ranks nothing
    value = pooled["value"]
    passed = None if value is None or not np.isfinite(value) else bool(value >= RETEST_TARGET)
    return _check("retest", value, pooled["ci"], f"Spearman >= {RETEST_TARGET}", passed,
                  grips=len(table), objects=int(table["object_id"].nunique()),
                  trials_per_set=settings.trials_per_set,
                  within_object_mean=float(ranked.mean()) if ranked.size else None)


def within_object_spearman(table: pd.DataFrame) -> pd.Series:
    """Per object of a :func:`retest_table`: Spearman of its grips' set-A against set-B means
    (NaN where either side is constant: the object ranks nothing)."""
    return pd.Series({name: _spearman(g["A"].to_numpy(float), g["B"].to_numpy(float))
                      for name, g in table.groupby("object_id")}, dtype=float)  # fmt: skip


def within_object_check(trials: pd.DataFrame, trials_per_set: int, resamples: int = 2000,
                        seed: int = 0) -> dict[str, Any]:
    """Mean over objects of the within-object Spearman, with a bootstrap interval resampling
    objects; objects with a constant side are skipped and counted."""
    target = (f"mean within-object Spearman >= {RETEST_TARGET} at {trials_per_set} trials "
              "per set (dataset.trials)")
    table = retest_table(trials, trials_per_set, part="within_object")
    if not {"A", "B"} <= set(table.columns):
        return _check("within_object", None, [None, None], target, None, objects=0, skipped=0,
                      grips=0, trials_per_set=trials_per_set, per_object=[])  # fmt: skip
    table = table.dropna(subset=["A", "B"])
    rho = within_object_spearman(table)
    scored = rho.dropna().to_numpy()
    value = float(scored.mean()) if scored.size else None
    grips = table.groupby("object_id").size()
    per_object = [{"object_id": name, "grips": int(grips[name]),
                   "spearman": None if np.isnan(r) else float(r)} for name, r in rho.items()]
    verdict = None if value is None or scored.size < WITHIN_SCORED else bool(
        value >= RETEST_TARGET)  # a verdict needs WITHIN_SCORED objects scored
    return _check("within_object", value, mean_bootstrap(scored, resamples, seed), target,
                  verdict,
                  objects=int(scored.size), skipped=int(rho.isna().sum()), grips=len(table),
                  trials_per_set=trials_per_set, per_object=per_object)  # fmt: skip


def icc_check(trials: pd.DataFrame) -> dict[str, Any]:
    """ICC(1) of per-trial robustness over the retest grips (all trials of both sets)."""
    rows = trials[trials["part"] == "retest"]
    table = rows.pivot_table(index="grip", columns="trial", values="robustness").dropna()
    if table.shape[0] < 2 or table.shape[1] < 2:
        return _check("icc", None, [None, None], f"ICC(1) >= {ICC_TARGET}", None)
    result = icc1(table.to_numpy())
    passed = None if result["value"] is None else bool(result["value"] >= ICC_TARGET)
    residual = rows["robustness"] - rows.groupby("grip")["robustness"].transform("mean")
    return _check("icc", result["value"], result["ci"], f"ICC(1) >= {ICC_TARGET}", passed,
                  grips=result["n"], trials=result["k"],
                  friction_residual_spearman=_spearman(rows["friction"].to_numpy(float),
                                                       residual.to_numpy(float)))  # fmt: skip


def decile_table(table: pd.DataFrame, column: str, bins: int = 10) -> pd.DataFrame:
    """Per quantile bin of ``column`` (1 = lowest = best): grips, mean robustness, mean success."""
    _require(table, (column, "robustness_mean", "object_id"))
    bin_of = _bins(table, column, bins)
    grouped = table.assign(bin=bin_of).groupby("bin")
    frame = pd.DataFrame({"grips": grouped.size(),
                          f"{column}_min": grouped[column].min(),
                          f"{column}_max": grouped[column].max(),
                          "robustness_mean": grouped["robustness_mean"].mean()})  # fmt: skip
    if "success_rate" in table.columns:
        frame["success_rate"] = grouped["success_rate"].mean()
    return frame


def decile_check(table: pd.DataFrame, column: str = "Q_C", bins: int = 10, resamples: int = 2000,
                 seed: int = 0) -> dict[str, Any]:
    """Spearman of bin number against the bin's mean robustness, object-cluster bootstrap CI.

    Bins are fixed on the whole table; each resample draws objects with replacement and
    recomputes the bins' means (and per-bin 95% intervals for the chart).
    """
    frame = decile_table(table, column, bins)
    bin_of = _bins(table, column, bins).to_numpy() - 1
    objects, object_of = np.unique(table["object_id"].astype(str), return_inverse=True)
    n_bins = int(bin_of.max()) + 1
    sums = np.zeros((objects.size, n_bins))
    counts = np.zeros((objects.size, n_bins))
    np.add.at(sums, (object_of, bin_of), table["robustness_mean"].to_numpy(float))
    np.add.at(counts, (object_of, bin_of), 1.0)
    rng = np.random.default_rng(seed)
    weights = rng.multinomial(objects.size, np.full(objects.size, 1.0 / objects.size), resamples)
    with np.errstate(invalid="ignore", divide="ignore"):
        boot_means = (weights @ sums) / (weights @ counts)
    order = np.arange(1, n_bins + 1)
    value = _spearman(order, frame["robustness_mean"].to_numpy())
    boot = np.array([_spearman(order[np.isfinite(m)], m[np.isfinite(m)]) for m in boot_means])
    boot = boot[np.isfinite(boot)]
    frame["ci_low"] = np.nanpercentile(boot_means, 2.5, axis=0)
    frame["ci_high"] = np.nanpercentile(boot_means, 97.5, axis=0)
    pooled = _spearman(table[column].to_numpy(float), table["robustness_mean"].to_numpy(float))
    passed = None if not np.isfinite(value) else bool(value <= DECILE_TARGET)
    target = f"Spearman(decile, mean robustness) <= {DECILE_TARGET}"
    return _check(f"decile_{column}", value,
                  np.percentile(boot, [2.5, 97.5]).tolist() if boot.size else [None, None],
                  target if column == "Q_C" else "for comparison with Q_C (no target)",
                  passed if column == "Q_C" else None,
                  pooled_grip_spearman=pooled, grips=len(table),
                  objects=int(objects.size), deciles=frame.reset_index().to_dict(orient="records"))


def _bins(table: pd.DataFrame, column: str, bins: int) -> pd.Series:
    ranks = table[column].rank(method="first")
    return pd.qcut(ranks, q=min(bins, len(table)), labels=False) + 1


def _require(table: pd.DataFrame, columns: tuple[str, ...]) -> None:
    missing = [c for c in columns if c not in table.columns]
    if missing:
        raise ValueError(f"table lacks column(s) {', '.join(missing)} (a dataset with the "
                         "graded outcome is needed: regenerate it)")


# -------------------------------------------------------------------------------------- entry
def calibrate(
    config: Config | None = None,
    settings: CalibrationSettings | None = None,
    dataset: pd.DataFrame | None = None,
    log: Callable[[str], None] = lambda message: None,
) -> tuple[dict[str, Any], pd.DataFrame]:
    """Run the checks; returns (JSON-able result, the long table of calibration trials)."""
    config = config or Config()
    settings = settings or CalibrationSettings()
    trials = run_calibration_trials(config, settings, log)
    reference = float(config.sim.reference_level_g)
    checks = [design_check(trials, reference, config), cone_check(trials),
              retest_check(trials, settings), icc_check(trials)]  # fmt: skip
    if settings.within_objects:
        checks.append(within_object_check(trials, config.dataset.trials, settings.bootstrap,
                                          settings.seed))  # fmt: skip
    if dataset is not None:
        checks += dataset_checks(dataset, settings)
    result = {"label_model": label_model_for(config.sim.engine),
              "reference_level_g": reference, "mu": float(config.grasp.mu),
              "settings": asdict(settings), "trials": len(trials),
              "checks": {c["name"]: c for c in checks},
              "config": config.model_dump(mode="json")}  # fmt: skip
    return result, trials


def dataset_checks(dataset: pd.DataFrame, settings: CalibrationSettings | None = None,
                   ) -> list[dict[str, Any]]:
    """The decile checks (Q_C, then Q_G for comparison) on a dataset with robustness."""
    settings = settings or CalibrationSettings()
    return [decile_check(dataset, column, resamples=settings.bootstrap, seed=settings.seed)
            for column in ("Q_C", "Q_G")]
