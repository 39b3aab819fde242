"""Plain per-grip Python version of the twelve features, and random grip tables to test with.

Written independently of ``grip_env.planning.features`` (law of cosines, explicit loops,
``math`` only) so
that the two can check each other; it is also the slow side of the feature benchmark.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from grip_env.columns import DESCRIPTORS
from grip_env.params import GraspParams
from grip_env.planning.features import OUTPUT_NAMES


def reference_features(table: pd.DataFrame, params: GraspParams) -> pd.DataFrame:
    """Features of every row, one grip at a time."""
    rows = [reference_row(row, params) for row in table.to_dict("records")]
    return pd.DataFrame(rows, index=table.index, columns=list(OUTPUT_NAMES))


def reference_row(row: dict, params: GraspParams) -> dict[str, float]:
    """The twelve features and two indexes of one grip (a dict of descriptor columns)."""
    p = [(row[f"p{i}_x"], row[f"p{i}_y"]) for i in (1, 2, 3)]
    n = [(row[f"n{i}_x"], row[f"n{i}_y"]) for i in (1, 2, 3)]
    f = [(row[f"f{i}_x"], row[f"f{i}_y"]) for i in (1, 2, 3)]
    two = bool(row["two_finger"])
    centre = (row["centroid_x"], row["centroid_y"])
    size = row["semi_major"] + row["semi_minor"]
    c_t = (sum(q[0] for q in p) / 3.0, sum(q[1] for q in p) / 3.0)
    c_g = c_t if two else (row["cg_x"], row["cg_y"])
    c_c = c_t if two else (row["cc_x"], row["cc_y"])
    e = [row["e1"], row["e2"], row["e3"]]
    nu = math.atan(params.mu)

    values = {
        "S1": _s1(p, two),
        "S2": _s2(p, row["area"], params.weight),
        "S3": _s3(p, row, params.lam),
        "S4": 1.0 - (row["rho1"] + row["rho2"] + row["rho3"]),
        "G1": 0.0 if two else _g1(n),
        "G2": 2.0 * params.weight * math.dist(c_g, centre) / size,
        "C1": _c1(f, n, nu),
        "C2": 0.0 if two else math.dist(c_g, c_c) / (params.eta * params.mu / 2.0),
        "C3": ((e[0] - e[1]) ** 2 + (e[1] - e[2]) ** 2 + (e[2] - e[0]) ** 2) / params.eta**2,
        "C4": _c4(row["spread"]),
        "C5": 2.0 * params.weight * math.dist(c_c, centre) / size,
        "C6": sum(max(ei - params.eta, 0.0) for ei in e),
    }
    cap = params.feature_cap
    capped = {k: (v if v <= cap else cap) for k, v in values.items()}  # NaN fails <=
    grasp = ("S1", "S2", "S3", "S4", "G1", "G2")
    config = ("S1", "S2", "S3", "S4", "C1", "C2", "C3", "C4", "C5", "C6")
    capped["Q_G"] = sum(capped[k] for k in grasp)
    capped["Q_C"] = sum(capped[k] for k in config)
    return capped


def _s1(p: list[tuple[float, float]], two: bool) -> float:
    a = math.dist(p[1], p[2])  # side opposite P1
    b = math.dist(p[0], p[2])  # opposite P2
    c = math.dist(p[0], p[1])  # opposite P3
    if min(a, b, c) == 0.0:
        return 2.0
    at_p1 = _law_of_cosines(b, c, a)
    at_p2 = _law_of_cosines(a, c, b)
    at_p3 = math.pi - at_p1 - at_p2
    if two:
        return 2.0 / math.pi * (abs(at_p1 - at_p2) + at_p3)
    return 3.0 / (2.0 * math.pi) * sum(abs(x - math.pi / 3.0) for x in (at_p1, at_p2, at_p3))


def _law_of_cosines(side1: float, side2: float, opposite: float) -> float:
    cosine = (side1**2 + side2**2 - opposite**2) / (2.0 * side1 * side2)
    return math.acos(max(-1.0, min(1.0, cosine)))


def _s2(p: list[tuple[float, float]], area: float, weight: float) -> float:
    (x1, y1), (x2, y2), (x3, y3) = p
    triangle = abs(x1 * (y2 - y3) + x2 * (y3 - y1) + x3 * (y1 - y2)) / 2.0
    return math.inf if triangle == 0.0 else weight * area / (4.0 * triangle)


def _s3(p: list[tuple[float, float]], row: dict, lam: float) -> float:
    total = 0.0
    for i in (1, 2, 3):
        for end in ("a", "b"):
            d = math.dist(p[i - 1], (row[f"r{i}{end}_x"], row[f"r{i}{end}_y"]))
            if d == 0.0:
                return math.inf
            if d < lam:
                total += lam / d - 1.0
    return total


def _g1(n: list[tuple[float, float]]) -> float:
    angles = [math.atan2(y, x) % (2.0 * math.pi) for x, y in n]
    product = 1.0
    for i, angle in enumerate(angles):
        others = [(other - angle) % (2.0 * math.pi) for j, other in enumerate(angles) if j != i]
        gap = min(others)  # counter-clockwise gap to the next direction
        if gap >= math.pi:
            return math.inf
        product *= math.pi - gap
    return (math.pi**3 / 27.0) / product - 1.0


def _c1(f: list[tuple[float, float]], n: list[tuple[float, float]], nu: float) -> float:
    deltas = []
    for (fx, fy), (nx, ny) in zip(f, n, strict=True):
        cosine = (fx * nx + fy * ny) / (math.hypot(fx, fy) * math.hypot(nx, ny))
        deltas.append(math.acos(max(-1.0, min(1.0, cosine))))
    k = 3.0 if any(d > nu for d in deltas) else 1.0
    return 4.0 * k / 3.0 * sum(d * d for d in deltas) / nu**2


def _c4(theta: float) -> float:
    if theta <= math.pi / 3.0:
        return 0.0
    if theta >= math.pi / 2.0:
        return math.inf
    return (math.pi / 6.0) / (math.pi / 2.0 - theta) - 1.0


# ------------------------------------------------------------------------------- random tables
def random_grip_table(count: int, seed: int = 0, two_finger_share: float = 0.2) -> pd.DataFrame:
    """``count`` random but plausible grips with every descriptor column (features not filled)."""
    rng = np.random.default_rng(seed)
    two = rng.random(count) < two_finger_share
    columns: dict[str, np.ndarray] = {}
    focus = rng.uniform(-30.0, 30.0, (count, 2))
    around = rng.uniform(-np.pi, np.pi, (count, 1)) + rng.normal(
        np.arange(3) * 2.0 * np.pi / 3.0, 0.6, (count, 3)
    )
    reach = rng.uniform(15.0, 70.0, (count, 3, 1))
    p = focus[:, None, :] + reach * np.stack([np.cos(around), np.sin(around)], axis=-1)
    to_focus = focus[:, None, :] - p
    normal_angle = np.arctan2(to_focus[..., 1], to_focus[..., 0]) + rng.normal(0.0, 0.4, (count, 3))
    deviation = rng.uniform(-0.6, 0.6, (count, 3))
    along = rng.uniform(-25.0, 5.0, (count, 3)), rng.uniform(-5.0, 25.0, (count, 3))
    tangent = np.stack([-np.sin(normal_angle), np.cos(normal_angle)], axis=-1)
    ends = [p + along[k][..., None] * tangent for k in (0, 1)]
    # two-finger rows: fingers 1 and 2 on one region (finger 1's), finger 2 further along it
    for end in ends:
        end[two, 1] = end[two, 0]
    normal_angle[two, 1] = normal_angle[two, 0]
    p[two, 1] = ends[0][two, 0] + 0.7 * (ends[1][two, 0] - ends[0][two, 0])
    p[two, 0] = ends[0][two, 0] + 0.2 * (ends[1][two, 0] - ends[0][two, 0])
    force_angle = normal_angle + deviation
    for i in range(3):
        k = str(i + 1)
        columns[f"p{k}_x"], columns[f"p{k}_y"] = p[:, i, 0], p[:, i, 1]
        columns[f"n{k}_x"], columns[f"n{k}_y"] = (
            np.cos(normal_angle[:, i]),
            np.sin(normal_angle[:, i]),
        )
        columns[f"f{k}_x"], columns[f"f{k}_y"] = (
            np.cos(force_angle[:, i]),
            np.sin(force_angle[:, i]),
        )
    for i in range(3):
        for e, end in zip("ab", ends, strict=True):
            columns[f"r{i + 1}{e}_x"], columns[f"r{i + 1}{e}_y"] = end[:, i, 0], end[:, i, 1]
    rho = rng.uniform(-0.3, 0.3, (count, 3))
    rho[two, 1] = rho[two, 0]
    for i in range(3):
        columns[f"rho{i + 1}"] = rho[:, i]
    real_focus = focus + rng.normal(0.0, 10.0, (count, 2))
    for name, values in (("cg", focus), ("cc", real_focus)):
        columns[f"{name}_x"] = np.where(two, np.nan, values[:, 0])
        columns[f"{name}_y"] = np.where(two, np.nan, values[:, 1])
    for i in range(3):
        columns[f"e{i + 1}"] = rng.uniform(30.0, 130.0, count)
    columns["spread"] = np.where(two, rng.uniform(0.0, 0.2, count), rng.uniform(0.0, 1.7, count))
    columns["hand_x"], columns["hand_y"] = rng.uniform(-80, 80, count), rng.uniform(-80, 80, count)
    columns["hand_yaw"] = rng.uniform(-np.pi, np.pi, count)
    columns["area"] = rng.uniform(2000.0, 15000.0, count)
    columns["centroid_x"] = rng.uniform(-10.0, 10.0, count)
    columns["centroid_y"] = rng.uniform(-10.0, 10.0, count)
    semi_minor = rng.uniform(20.0, 50.0, count)
    columns["semi_minor"] = semi_minor
    columns["semi_major"] = semi_minor + rng.uniform(0.0, 40.0, count)
    table = pd.DataFrame({name: columns[name] for name in DESCRIPTORS})
    table.insert(0, "two_finger", two)
    return table
