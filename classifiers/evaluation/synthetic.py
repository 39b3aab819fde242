"""A synthetic grip table with the dataset's columns, for tests and benchmarks.

Success depends learnably on the features (logistic in C1, C4, S3 and S2, an object effect and
noise), outcomes are binomial over ``trials``; the graded outcome (``robustness_mean``,
``robustness_std``, in g) is log-normal per trial about a level set by the same logit. Geometry
is a consistent toy: each object is a disc, contacts lie on its rim and the normals point
(roughly) inwards, so ε can be computed from a row.
The real dataset (``grip_env.dataset.load``) replaces it.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from grip_env.columns import DATASET_COLUMNS, FEATURES


def synthetic_grips(
    n_objects: int = 40, grips: tuple[int, int] = (10, 40), trials: int = 5, seed: int = 0
) -> pd.DataFrame:
    """A grip table of ``n_objects`` objects with ``grips[0]..grips[1]`` grips each."""
    if n_objects < 1 or grips[0] < 1 or grips[1] < grips[0] or trials < 1:
        raise ValueError(f"bad sizes: n_objects={n_objects}, grips={grips}, trials={trials}")
    rng = np.random.default_rng(seed)
    counts = rng.integers(grips[0], grips[1] + 1, size=n_objects)
    object_id = np.repeat(np.arange(n_objects), counts)
    n = object_id.size
    radius = rng.uniform(30.0, 70.0, size=n_objects)[object_id]
    centre = rng.uniform(-20.0, 20.0, size=(n_objects, 2))[object_id]
    table = {"object_id": object_id, "grasp_id": np.arange(n) // 3, "grip_id": np.arange(n)}
    table["two_finger"] = rng.random(n) < 0.2
    table.update(_geometry(rng, n, radius, centre))
    features = _features(rng, n, table["two_finger"])
    table.update(features)
    table["Q_G"] = sum(features[f] for f in ("S1", "S2", "S3", "S4", "G1", "G2"))
    table["Q_C"] = sum(features[f] for f in FEATURES if f[0] in "SC")
    object_effect = rng.normal(0.0, 0.5, size=n_objects)[object_id]
    logit = (
        2.0 - 1.6 * features["C1"] - 1.2 * features["C4"] - 0.8 * features["S3"]
        - 0.8 * features["S2"] + object_effect + rng.normal(0.0, 0.3, size=n)
    )  # fmt: skip
    successes = rng.binomial(trials, 1.0 / (1.0 + np.exp(-logit)))
    table.update(trials=np.full(n, trials), successes=successes)
    table["success_rate"] = successes / trials
    table["success"] = table["success_rate"] >= 0.5
    table.update(_robustness(rng, logit, trials))
    frame = pd.DataFrame(table)
    return frame[list(DATASET_COLUMNS)]


def _robustness(rng: np.random.Generator, logit: np.ndarray, trials: int) -> dict:
    """Per-trial levels log-normal about ``exp(logit / 2)`` g; a trial that never lifts scores 0."""
    level = np.exp(0.5 * logit[:, None] + rng.normal(0.0, 0.4, size=(logit.size, trials)))
    lifted = rng.random((logit.size, trials)) >= 1.0 / (1.0 + np.exp(logit[:, None] + 2.0))
    per_trial = np.where(lifted, level, 0.0)
    spread = per_trial.std(axis=1, ddof=1) if trials > 1 else np.zeros(logit.size)
    return {"robustness_mean": per_trial.mean(axis=1), "robustness_std": spread}


def _geometry(rng: np.random.Generator, n: int, radius: np.ndarray, centre: np.ndarray) -> dict:
    base = rng.uniform(0.0, 2 * np.pi, size=n)
    gaps = rng.uniform(0.5, 2.6, size=(n, 2))
    angles = np.stack([base, base + gaps[:, 0], base + gaps[:, 0] + gaps[:, 1]], axis=1)
    rim = np.stack([np.cos(angles), np.sin(angles)], axis=2)
    points = centre[:, None, :] + radius[:, None, None] * rim
    tilt = rng.normal(0.0, 0.15, size=(n, 3))
    normal_angle = angles + np.pi + tilt
    normals = np.stack([np.cos(normal_angle), np.sin(normal_angle)], axis=2)
    forces_angle = normal_angle + rng.normal(0.0, 0.2, size=(n, 3))
    forces = np.stack([np.cos(forces_angle), np.sin(forces_angle)], axis=2)
    out: dict = {}
    for i in range(3):
        for k, axis in enumerate("xy"):
            out[f"p{i + 1}_{axis}"] = points[:, i, k]
            out[f"n{i + 1}_{axis}"] = normals[:, i, k]
            out[f"f{i + 1}_{axis}"] = forces[:, i, k]
            for end, shift in (("a", -5.0), ("b", 5.0)):
                out[f"r{i + 1}{end}_{axis}"] = points[:, i, k] + shift * rim[:, i, 1 - k]
        out[f"rho{i + 1}"] = rng.normal(0.0, 0.05, size=n)
        out[f"e{i + 1}"] = rng.uniform(40.0, 130.0, size=n)
    for name in ("cg_x", "cg_y", "cc_x", "cc_y"):
        out[name] = centre[:, 0 if name.endswith("x") else 1] + rng.normal(0.0, 5.0, size=n)
    out.update(
        spread=rng.uniform(0.0, 1.5, size=n), hand_x=centre[:, 0], hand_y=centre[:, 1],
        hand_yaw=rng.uniform(-np.pi, np.pi, size=n), area=np.pi * radius**2,
        centroid_x=centre[:, 0], centroid_y=centre[:, 1], semi_major=radius, semi_minor=radius,
    )  # fmt: skip
    return out


def _features(rng: np.random.Generator, n: int, two_finger: np.ndarray) -> dict[str, np.ndarray]:
    features = {name: rng.gamma(2.0, 0.3, size=n) for name in FEATURES}
    features["C4"] = np.where(rng.random(n) < 0.6, 0.0, rng.gamma(1.5, 0.5, size=n))
    features["G1"] = np.where(two_finger, 0.0, features["G1"])
    features["C2"] = np.where(two_finger, 0.0, features["C2"])
    return features
