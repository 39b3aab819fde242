"""Agreement between engines: a dataset's grips simulated again in the other engine.

Every recorded grip of a seeded sample of objects (as ``retest`` samples them) runs its
``dataset.trials`` trials in the dataset's own engine and in the other one, with the same grips,
the same draws (trials 0..T-1 of the dataset's seed) and the same protocol; with ``ceilings``
each engine also runs trials T..2T-1, its own within-object retest (the ceiling any agreement
between engines can reach). The own engine's first run is the recorded labels again (checked:
``reproduced`` counts the grips whose mean robustness is the recorded one). Reported, over all
objects, by family (mesh, procedural, named...), by the grips an object kept and by how many convex
pieces its simulated body is made of, with 95 % bootstrap intervals over objects:

* per-trial success agreement and Cohen's kappa, and each engine's mean robustness (how much one
  engine holds more than the other on the same trials);
* the pooled Spearman of the grips' mean robustness, and its mean within objects, beside each
  engine's own within-object retest;
* top-1, both ways: how often the grip one engine ranks first (by mean robustness) succeeds in
  most of its trials in the other (grips tied first count equally, as a pick among them would);
* with ``ceilings``, how much of a label's differences between the grips of an object is the
  grip, the engine and the draws (:mod:`grip_env.dataset.label_shares`, from both engines'
  2T trials a grip);
* each engine's cost: CPU seconds a trial and a protocol step (of the worker processes), and a
  trustworthy label's: the trials that bring its within-object retest to ``TRUSTWORTHY`` times a
  trial's cost, both by Spearman-Brown from the retest at T trials and as measured at every label
  size from 1 to T (:mod:`grip_env.dataset.retest_curve`).

Each object's outcomes are kept in ``parts`` (when given) as it finishes: an interrupted run
given the same folder again simulates only the objects not done, and after a new label model of
one engine only that engine's runs (an engine's runs depend on its own label model alone; its
CPU seconds are then those of the run that made them).
"""

from __future__ import annotations

import json
import math
import time
import zlib
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from grip_env.config import ENGINES
from grip_env.dataset.files import write_text_atomically
from grip_env.dataset.label_shares import SHARES, grip_components, label_shares
from grip_env.dataset.manifest import fingerprint, read_manifest
from grip_env.dataset.resimulation import BOOTSTRAP, _map, _ObjectCheck, _retest_sample
from grip_env.dataset.retest_curve import TRUSTWORTHY, retest_curve, trials_for, trials_measured
from grip_env.label_model import engine_of, label_model_for, label_model_of
from grip_env.objects.family import object_family

#: The outcome columns an object's part keeps for each run.
_KEPT = ("grip", "trial", "robustness", "success", "steps")
#: Per-object scores, each averaged over objects (NaN where an object gives none).
_SCORES = ("spearman", "top_own", "top_other", "retest_own", "retest_other")


@dataclass
class Agreement:
    """The engines' agreement on a group of objects; each ``*_interval`` a 95 % bootstrap
    interval over the objects."""

    objects: int
    grips: int
    trials: int
    agreement: float  # share of trials both engines judge alike (success)
    agreement_interval: tuple[float, float]
    kappa: float
    kappa_interval: tuple[float, float]
    pooled: float  # Spearman of the grips' mean robustness, all the group's grips together
    pooled_interval: tuple[float, float]
    within: float  # mean over objects of the within-object Spearman between engines
    within_interval: tuple[float, float]
    top1_own: float  # share of objects whose own-engine first grip mostly succeeds in the other
    top1_own_interval: tuple[float, float]
    top1_other: float  # ... whose other-engine first grip mostly succeeds in the own engine
    top1_other_interval: tuple[float, float]
    retest_own: float  # mean over objects of the own engine's within-object retest (ceiling)
    retest_own_interval: tuple[float, float]
    retest_other: float  # ... of the other engine's
    retest_other_interval: tuple[float, float]
    # shares of a label's variance between an object's grips (``label_shares``; with ceilings)
    share_grip: float  # the grip, alike in both engines
    share_grip_interval: tuple[float, float]
    share_engine: float  # the engine's own view of the grip
    share_engine_interval: tuple[float, float]
    share_draws: float  # the trials' draws the label averages
    share_draws_interval: tuple[float, float]
    robustness_own: float  # mean robustness (g) of the group's trials in the own engine
    robustness_own_interval: tuple[float, float]
    robustness_other: float  # ... in the other engine
    robustness_other_interval: tuple[float, float]


@dataclass
class EngineCost:
    """What one engine's trials of the cross-check cost (CPU seconds of the worker processes)."""

    engine: str
    trials: int
    steps: int  # protocol steps (``sim.timestep`` each; MuJoCo subdivides them)
    cpu_seconds: float
    ms_per_trial: float
    us_per_step: float
    trials_for_trustworthy: float  # trials a grip for a within-object retest of TRUSTWORTHY
    core_seconds_per_label: float  # those trials (rounded up) times a trial's cost
    #: The within-object retest measured at 1..T trials a grip (``retest_curve``; empty without
    #: the retests), the fewest trials whose retest reaches TRUSTWORTHY in it
    #: (``trials_measured``) and those trials (rounded up) times a trial's cost.
    retest_by_trials: list[float] = field(default_factory=list)
    trials_measured: float = float("nan")
    core_seconds_measured: float = float("nan")


@dataclass
class CrossCheck:
    """How far a dataset's labels are the engine's: its engine against the other one."""

    engine: str
    other: str
    seed: int
    reproduced: int  # grips whose own-engine mean robustness is the recorded one, bit for bit
    overall: Agreement
    families: dict[str, Agreement] = field(default_factory=dict)
    cost: list[EngineCost] = field(default_factory=list)
    #: The objects that kept every grip the dataset allows (``dataset.max_grips_per_object``)
    #: against those that had fewer candidates: a within-object Spearman over a few grips that
    #: differ by a shift or a turn ranks near-equal grips in both engines (BENCHMARKS.md, "Mesh
    #: objects in the cross-check").
    by_grips: dict[str, Agreement] = field(default_factory=dict)
    #: The objects simulated as one convex prism against those cut into several: where pieces
    #: meet, each engine's contacts see a seam the real body does not have (BENCHMARKS.md, "Seams
    #: between convex pieces").
    by_pieces: dict[str, Agreement] = field(default_factory=dict)
    #: Each engine's label model, as this code made them (a recorded cross-check of other
    #: models is stale: ``tests/test_crosscheck.py`` checks the shipped one).
    label_models: dict[str, str] = field(default_factory=dict)

    def summary(self) -> str:
        o = self.overall
        a, w = o.agreement_interval, o.within_interval
        return (f"{self.engine} against {self.other} on {o.grips} grips of {o.objects} objects "
                f"({o.trials} trials; {self.reproduced} reproduced): success agree "
                f"{o.agreement:.1%} [{a[0]:.1%}, {a[1]:.1%}], kappa {o.kappa:.2f}, "
                f"within-object Spearman {o.within:.2f} [{w[0]:.2f}, {w[1]:.2f}] (retest "
                f"{self.engine} {o.retest_own:.2f}, {self.other} {o.retest_other:.2f}), pooled "
                f"{o.pooled:.2f}, top-1 {self.engine} in {self.other} {o.top1_own:.1%}, "
                f"{self.other} in {self.engine} {o.top1_other:.1%}{self._shares()}")

    def _shares(self) -> str:
        o = self.overall
        if not math.isfinite(o.share_grip):
            return ""
        return (f"; a label's differences between grips: the grip {o.share_grip:.0%}, the "
                f"engine {o.share_engine:.0%}, the draws {o.share_draws:.0%}")

    def as_dict(self) -> dict[str, Any]:
        """JSON-able, with the summary."""
        return {"summary": self.summary(), **asdict(self)}


def other_engine(engine: str) -> str:
    """The engine a dataset made in ``engine`` is cross-checked against."""
    return next(e for e in ENGINES if e != engine)


def check_crosscheckable(directory: Path) -> str:
    """The engine of the dataset in ``directory``, once it is sure this code can cross-check it.

    Raises:
        ValueError: an unknown engine, a label model this code does not make (its engine's),
            or an engine that is not installed.
    """
    from grip_env.sim.engine import require_engine

    manifest = read_manifest(directory)
    engine = engine_of(manifest)
    found, expected = label_model_of(manifest), label_model_for(engine)
    if found != expected:
        raise ValueError(f"dataset {directory} was labelled by label model {found!r}; this code "
                         f"makes {expected!r} in {engine}, so it cannot cross-check it "
                         f"(regenerate it first)")
    require_engine(engine)
    require_engine(other_engine(engine))
    return engine


def crosscheck(path: str | Path, objects: int, seed: int = 0, workers: int = 1,
               parts: str | Path | None = None, ceilings: bool = True) -> CrossCheck:
    """Simulate every grip of ``objects`` seeded objects in both engines and compare.

    Args:
        parts: a folder keeping each object's outcomes as it finishes (a rerun given it
            simulates only what is missing); None keeps nothing.
        ceilings: also run each engine's within-object retest (twice the trials).

    Raises:
        ValueError: ``objects`` is not a positive integer, the dataset is unreadable, or its
            label model is not one this code reproduces (its engine's).
    """
    directory = Path(path)
    engine = check_crosscheckable(directory)
    checks = _retest_sample(directory, objects, seed)
    key = _run_key(read_manifest(directory), ceilings)
    folder = None if parts is None else Path(parts)
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)
    runs = _map(_object_runs, [(check, folder, key) for check in checks], workers, "crosscheck")
    return _figures(checks, runs, engine, seed)


@dataclass
class _Runs:
    """One object's outcomes: per engine, trials 0..T-1 (``draws``) and T..2T-1 (``retest``,
    None without ceilings), and the CPU seconds each engine took."""

    draws: dict[str, pd.DataFrame]
    retest: dict[str, pd.DataFrame | None]
    seconds: dict[str, float]


def _run_key(manifest: dict[str, Any], ceilings: bool) -> dict[str, Any]:
    """What an object's outcomes depend on: a part made under another key is made again.

    The dataset enters by its grips (``grips``: the fingerprint of its run identity without the
    label model), each engine by its own label model: a change to one engine's labels (the
    dataset regenerated at a new PyBullet label model) keeps the other engine's runs."""
    identity = {k: v for k, v in (manifest.get("identity") or {}).items() if k != "label_model"}
    return {"grips": fingerprint(identity) if identity else manifest.get("fingerprint"),
            "ceilings": ceilings, "label_models": {e: label_model_for(e) for e in ENGINES}}


def _object_runs(item: tuple[_ObjectCheck, Path | None, dict[str, Any]]) -> _Runs:
    """One object's outcomes in both engines: each engine's from the object's part when it was
    made under this run's key for that engine, else simulated (and the part kept)."""
    check, folder, key = item
    file = None if folder is None else folder / f"{check.task.index:05d}.json"
    key = {**key, "object_id": check.task.object_id}
    stored = (json.loads(file.read_text(encoding="utf-8"))
              if file is not None and file.is_file() else {})  # fmt: skip
    kept = [e for e in ENGINES if stored and _same_runs(stored.get("key", {}), key, e)]
    if len(kept) == len(ENGINES):
        return _from_json(stored)
    runs = _simulate(check, key["ceilings"], _from_json(stored) if kept else None, kept)
    if file is not None:
        write_text_atomically(file, json.dumps({"key": key, **_to_json(runs)}) + "\n")
    return runs


def _same_runs(stored: dict[str, Any], key: dict[str, Any], engine: str) -> bool:
    """Whether a part made under ``stored`` holds ``engine``'s runs of ``key``: the same
    grips, object and retest setting, and that engine's label model."""
    same = all(stored.get(k) == key[k] for k in ("grips", "ceilings", "object_id"))
    models = stored.get("label_models") or {}
    return same and models.get(engine) == key["label_models"][engine]


def _simulate(check: _ObjectCheck, ceilings: bool, stored: _Runs | None = None,
              kept: list[str] | tuple[str, ...] = ()) -> _Runs:  # fmt: skip
    """Both engines' runs of one object (those of the engines in ``kept`` taken from
    ``stored``), each timed by the CPU of this process (where the trials run when its kernels
    are portable; else they run in the held worker, and the wall time of the call stands for
    their CPU)."""
    from grip_env.portable_math import math_is_portable
    from grip_env.sim import run_trial_outcomes

    clock = time.process_time if math_is_portable() else time.perf_counter
    config = check.task.config
    grips = check.recorded.assign(object_id=check.task.object_id).reset_index(drop=True)
    trials, seed = config.dataset.trials, config.dataset.seed
    draws, retest, seconds = {}, {}, {}
    for engine in (config.sim.engine, other_engine(config.sim.engine)):
        if stored is not None and engine in kept:
            draws[engine], retest[engine] = stored.draws[engine], stored.retest[engine]
            seconds[engine] = stored.seconds[engine]
            continue
        in_engine = config.override(sim={"engine": engine})
        started = clock()
        draws[engine] = run_trial_outcomes(check.task.obj, grips, in_engine, trials, seed)
        retest[engine] = (run_trial_outcomes(check.task.obj, grips, in_engine, trials, seed,
                                             trial_offset=trials) if ceilings else None)
        seconds[engine] = clock() - started
    return _Runs(draws, retest, seconds)


def _to_json(runs: _Runs) -> dict[str, Any]:
    def table(frame: pd.DataFrame | None) -> dict[str, list] | None:
        return None if frame is None else {c: frame[c].tolist() for c in _KEPT}

    return {"draws": {e: table(f) for e, f in runs.draws.items()},
            "retest": {e: table(f) for e, f in runs.retest.items()}, "seconds": runs.seconds}


def _from_json(stored: dict[str, Any]) -> _Runs:
    def frame(columns: dict[str, list] | None) -> pd.DataFrame | None:
        return None if columns is None else pd.DataFrame(columns).astype({"success": bool})

    return _Runs({e: frame(c) for e, c in stored["draws"].items()},  # type: ignore[misc]
                 {e: frame(c) for e, c in stored["retest"].items()}, stored["seconds"])


def _means(frame: pd.DataFrame, column: str = "robustness") -> np.ndarray:
    return frame.groupby("grip", sort=True)[column].mean().to_numpy()


def _spearman(a: np.ndarray, b: np.ndarray) -> float:
    from scipy import stats

    if len(a) < 2 or np.ptp(a) == 0 or np.ptp(b) == 0:
        return float("nan")
    return float(stats.spearmanr(a, b).statistic)


def _object_figures(runs: _Runs, engine: str, other: str) -> dict[str, Any]:
    """One object's sums and scores (trials alike, successes, the grips' means, retests)."""
    own, theirs = runs.draws[engine], runs.draws[other]
    a, b = own["success"].to_numpy(bool), theirs["success"].to_numpy(bool)
    mean_a, mean_b = _means(own), _means(theirs)
    rate_a, rate_b = _means(own, "success"), _means(theirs, "success")

    def retest(name: str) -> float:
        again = runs.retest.get(name)
        return float("nan") if again is None else _spearman(_means(runs.draws[name]),
                                                            _means(again))

    return {"trials": len(a), "alike": int((a == b).sum()), "a": int(a.sum()),
            "sums": (float(own["robustness"].sum()), float(theirs["robustness"].sum())),
            "components": _components(runs, (engine, other)), "label_trials": _trials(own),
            "b": int(b.sum()), "means": (mean_a, mean_b), "spearman": _spearman(mean_a, mean_b),
            "top_own": _first_holds(mean_a, rate_b), "top_other": _first_holds(mean_b, rate_a),
            "retest_own": retest(engine), "retest_other": retest(other)}


def _first_holds(ranked: np.ndarray, rates: np.ndarray) -> float:
    """Chance that the grip first by ``ranked`` succeeds in most trials by ``rates``: the share of
    the grips tied first that do (a uniform pick among them), not the first one listed. Means of
    the same levels summed in another order tie too (they differ in the last bits at most)."""
    first = np.isclose(ranked, ranked.max(), rtol=1e-9, atol=0.0)
    return float(np.mean(rates[first] > 0.5))


def _trials(frame: pd.DataFrame) -> int:
    """Trials a grip in one run (a label's)."""
    return int(frame.groupby("grip").size().max()) if len(frame) else 0


def _components(runs: _Runs, engines: tuple[str, str]) -> np.ndarray | None:
    """The object's per-trial variance components (``grip_components``) over both engines'
    every trial, or None without the retests or with fewer than two grips."""
    tables = [_every_trial(runs, engine) for engine in engines]
    if any(table is None for table in tables):
        return None
    outcomes = np.stack(tables, axis=1)
    return grip_components(outcomes) if outcomes.shape[0] >= 2 else None


def _reproduced(own: pd.DataFrame, check: _ObjectCheck) -> int:
    """Grips whose mean robustness in the own engine is the recorded one, bit for bit (summed
    as the dataset sums it: ``trial_summary``)."""
    from grip_env.sim.execution import trial_summary

    n = len(check.recorded)
    ordered = own.sort_values(["grip", "trial"], kind="stable")
    mean = trial_summary(ordered["robustness"].to_numpy(float).reshape(n, -1),
                         ordered["success"].to_numpy(bool).reshape(n, -1))["robustness_mean"]
    return int((mean == check.recorded["robustness_mean"].to_numpy()).sum())


def _kappa(rows: list[dict[str, Any]]) -> tuple[float, float]:
    """Per-trial agreement and Cohen's kappa over the objects ``rows``."""
    n = sum(r["trials"] for r in rows)
    if n == 0:
        return float("nan"), float("nan")
    observed = sum(r["alike"] for r in rows) / n
    pa, pb = sum(r["a"] for r in rows) / n, sum(r["b"] for r in rows) / n
    chance = pa * pb + (1 - pa) * (1 - pb)
    return observed, (observed - chance) / (1 - chance) if chance < 1 else float("nan")


def _group_values(rows: list[dict[str, Any]]) -> dict[str, float]:
    """The group's figures (each a point estimate) from its objects' ``rows``."""
    agreement, kappa = _kappa(rows)
    found = {"agreement": agreement, "kappa": kappa}
    if rows:
        found["pooled"] = _spearman(np.concatenate([r["means"][0] for r in rows]),
                                    np.concatenate([r["means"][1] for r in rows]))
    else:
        found["pooled"] = float("nan")
    trials = sum(r["trials"] for r in rows)
    for k, name in enumerate(("robustness_own", "robustness_other")):
        found[name] = sum(r["sums"][k] for r in rows) / trials if trials else float("nan")
    for score in _SCORES:
        values = np.array([r[score] for r in rows], float)
        found[score] = float(np.nanmean(values)) if np.isfinite(values).any() else float("nan")
    split = [r for r in rows if r.get("components") is not None]
    shares = (label_shares(np.sum([r["components"] for r in split], axis=0),
                           split[0]["label_trials"]) if split else np.full(3, np.nan))
    found.update({f"share_{name}": float(v) for name, v in zip(SHARES, shares, strict=True)})
    return found


def _group_stream(seed: int, group: str) -> np.random.Generator:
    """The bootstrap stream of one group (all objects, or a family), keyed by the seed and the
    group's name: a family's intervals do not depend on which other families the sample holds."""
    return np.random.default_rng([seed, zlib.crc32(group.encode())])


def _agreement(rows: list[dict[str, Any]], grips: int, rng: np.random.Generator) -> Agreement:
    """The group's figures with bootstrap intervals (objects resampled ``BOOTSTRAP`` times)."""
    point = _group_values(rows)
    if rows:
        picks = rng.integers(0, len(rows), (BOOTSTRAP, len(rows)))
        boot = [_group_values([rows[i] for i in pick]) for pick in picks]
    else:
        boot = []

    def interval(name: str) -> tuple[float, float]:
        values = np.array([b[name] for b in boot], float)
        values = values[np.isfinite(values)]
        if not len(values):
            return float("nan"), float("nan")
        return float(np.quantile(values, 0.025)), float(np.quantile(values, 0.975))

    named = {"spearman": "within", "top_own": "top1_own", "top_other": "top1_other"}
    figures: dict[str, Any] = {}
    for name, value in point.items():
        shown = named.get(name, name)
        figures[shown], figures[f"{shown}_interval"] = value, interval(name)
    return Agreement(len(rows), grips, int(sum(r["trials"] for r in rows)), **figures)


def _costs(runs: list[_Runs], engines: tuple[str, str], retests: dict[str, float],
           trials: int, seed: int) -> list[EngineCost]:
    """Each engine's cost a trial, a step and a trustworthy label (from Spearman-Brown and
    from the retest measured at each label size)."""
    costs = []
    for engine in engines:
        frames = [f for r in runs for f in (r.draws[engine], r.retest.get(engine))
                  if f is not None]
        count = int(sum(len(f) for f in frames))
        steps = int(sum(f["steps"].sum() for f in frames))
        seconds = float(sum(r.seconds[engine] for r in runs))
        per_trial = seconds / count if count else float("nan")
        needed = trials_for(retests[engine], trials)
        curve = retest_curve(_retest_outcomes(runs, engine), seed=seed)
        measured = trials_measured(curve, TRUSTWORTHY)
        costs.append(EngineCost(engine, count, steps, seconds, 1e3 * per_trial,
                                1e6 * seconds / steps if steps else float("nan"), needed,
                                _label_cost(needed, per_trial), [float(v) for v in curve],
                                measured, _label_cost(measured, per_trial)))
    return costs


def _every_trial(runs: _Runs, engine: str) -> np.ndarray | None:
    """One object's robustness in ``engine`` over both runs, (grips, 2T) in grip and trial
    order; None without the retest."""
    again = runs.retest.get(engine)
    if again is None:
        return None
    both = pd.concat([runs.draws[engine], again])
    return (both.pivot(index="grip", columns="trial", values="robustness")
            .sort_index().sort_index(axis=1).to_numpy(float))


def _retest_outcomes(runs: list[_Runs], engine: str) -> list[np.ndarray]:
    """Each retested object's robustness in ``engine``, (grips, 2T)."""
    return [m for m in (_every_trial(r, engine) for r in runs) if m is not None]


def _label_cost(trials: float, per_trial: float) -> float:
    """A label of ``trials`` (rounded up) at ``per_trial`` core-seconds a trial."""
    return math.ceil(trials) * per_trial if math.isfinite(trials) else float("nan")


def _figures(checks: list[_ObjectCheck], runs: list[_Runs], engine: str,
             seed: int) -> CrossCheck:
    other = other_engine(engine)
    rows = [_object_figures(r, engine, other) for r in runs]
    grips = [len(c.recorded) for c in checks]
    overall = _agreement(rows, sum(grips), _group_stream(seed, "all objects"))
    groups: dict[str, list[int]] = {}
    for i, check in enumerate(checks):
        groups.setdefault(object_family(check.task.obj), []).append(i)

    def agreements(named: dict[str, list[int]], stream: str = "") -> dict[str, Agreement]:
        """Each non-empty group's agreement, its bootstrap stream keyed by its name."""
        return {name: _agreement([rows[i] for i in members], sum(grips[i] for i in members),
                                 _group_stream(seed, stream + name))
                for name, members in named.items() if members}

    families = agreements(dict(sorted(groups.items())), "family ")
    by_grips = agreements(_by_grip_count(checks, grips))
    by_pieces = agreements(_by_pieces(checks))
    reproduced = sum(_reproduced(r.draws[engine], c) for r, c in zip(runs, checks, strict=True))
    trials = checks[0].task.config.dataset.trials if checks else 0
    cost = _costs(runs, (engine, other), {engine: overall.retest_own,
                                          other: overall.retest_other}, trials, seed)
    return CrossCheck(engine, other, seed, reproduced, overall, families, cost, by_grips,
                      by_pieces, {e: label_model_for(e) for e in (engine, other)})


def _by_grip_count(checks: list[_ObjectCheck], grips: list[int]) -> dict[str, list[int]]:
    """The objects (indices) that kept the dataset's most grips an object, and the rest."""
    if not checks:
        return {}
    cap = checks[0].task.config.dataset.max_grips_per_object
    return {f"{cap} grips": [i for i, n in enumerate(grips) if n >= cap],
            f"under {cap} grips": [i for i, n in enumerate(grips) if n < cap]}


def _by_pieces(checks: list[_ObjectCheck]) -> dict[str, list[int]]:
    """The objects (indices) whose simulated body is one convex prism, and those of several."""
    def pieces(check: _ObjectCheck) -> int:
        tolerance = check.task.config.objects.sim_tolerance_mm
        return len(check.task.obj.simulated_shape(tolerance).pieces)

    counts = [pieces(check) for check in checks]
    return {"one convex piece": [i for i, n in enumerate(counts) if n == 1],
            "several convex pieces": [i for i, n in enumerate(counts) if n > 1]}
