"""How close planning on the rendered contour comes to planning on the polygon, per object.

For each object and image resolution: the regions' count on both contours, the largest distance
between a true region's endpoints and its perceived twin's (mm and px), and the relative error
of the best grip's Q_C.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from grip_env.config import Config
from grip_env.objects import PlanarObject
from grip_env.perception.regions import Regions, find_regions
from grip_env.sim.camera import image_scale, perceive


def endpoint_errors(true: Regions, perceived: Regions) -> np.ndarray:
    """Distance (mm) of each true region's endpoints to its perceived twin's (the perceived
    region nearest by both endpoints)."""
    if len(true) == 0 or len(perceived) == 0:
        return np.zeros(0)
    cost = (np.linalg.norm(perceived.a[None] - true.a[:, None], axis=2)
            + np.linalg.norm(perceived.b[None] - true.b[:, None], axis=2))
    twin = cost.argmin(axis=1)
    return np.concatenate([np.linalg.norm(perceived.a[twin] - true.a, axis=1),
                           np.linalg.norm(perceived.b[twin] - true.b, axis=1)])


def resolution_sweep(
    objects: Sequence[PlanarObject], resolutions: Sequence[int], config: Config | None = None,
) -> pd.DataFrame:
    """One row per (resolution, object): regions, endpoint error, best-grip Q_C on both contours.

    The image scale is ``config.perception.mm_per_px`` scaled by 256 / resolution, so every
    resolution sees the object at the same size in the image's frame (the default 256 px at
    1 mm/px covers a 247 mm field).
    """
    from grip_env.planning.pipeline import candidates
    from grip_env.sim.world import World

    config = config or Config()
    rows = []
    with World() as world:
        truth = {o.name: (find_regions(o, config.perception, config.grasp),
                          _best(candidates(o, config=config))) for o in objects}
        for resolution in resolutions:
            scale = config.perception.mm_per_px * 256 / resolution
            run = config.override(perception={"resolution_px": int(resolution), "mm_per_px": scale})
            for obj in objects:
                seen = perceive(obj, run.perception, config.objects.thickness_mm, world=world)
                used_scale = image_scale(obj, run.perception)
                regions = find_regions(seen, run.perception, config.grasp)
                true_regions, true_best = truth[obj.name]
                errors = endpoint_errors(true_regions, regions)
                best = _best(candidates(seen, config=run))
                rows.append({
                    "resolution_px": int(resolution), "mm_per_px": used_scale, "object": obj.name,
                    "true_regions": len(true_regions), "seen_regions": len(regions),
                    "endpoint_error_mm": float(errors.max()) if len(errors) else np.nan,
                    "endpoint_error_px": (float(errors.max()) / used_scale if len(errors)
                                          else np.nan),
                    "true_best_qc": true_best, "seen_best_qc": best,
                    "qc_rel_error": abs(best - true_best) / true_best,
                })
    return pd.DataFrame(rows)


def sweep_summary(table: pd.DataFrame) -> pd.DataFrame:
    """Per resolution: share of objects whose region count matches, median and largest endpoint
    error (px, mm), share within 2 px, and the median and largest best-grip Q_C error."""
    def summary(group: pd.DataFrame) -> pd.Series:
        match = group["true_regions"] == group["seen_regions"]
        both = np.isfinite(group["qc_rel_error"])
        return pd.Series({
            "objects": len(group), "mm_per_px": group["mm_per_px"].median(),
            "regions_match": f"{int(match.sum())}/{len(group)}",
            "endpoint_px_median": group["endpoint_error_px"].median(),
            "endpoint_px_max": group.loc[match, "endpoint_error_px"].max(),
            "endpoint_mm_max": group.loc[match, "endpoint_error_mm"].max(),
            "within_2px": f"{int((match & (group['endpoint_error_px'] <= 2)).sum())}/{len(group)}",
            "qc_error_median": group.loc[both, "qc_rel_error"].median(),
            "qc_error_max": group.loc[both, "qc_rel_error"].max(),
            "qc_within_10pct":
                f"{int((group.loc[both, 'qc_rel_error'] <= 0.10).sum())}/{int(both.sum())}",
        })
    return table.groupby("resolution_px").apply(summary, include_groups=False)


def _best(table: pd.DataFrame) -> float:
    return float(table["Q_C"].min()) if len(table) else np.nan
