"""From a planar object to its candidate grips: regions, grasps, configurations, features.

``candidates(obj)`` returns one row per Barrett configuration with DESIGN's candidate columns
(``grip_env.columns.CANDIDATE_COLUMNS``), best first by Q_C. The features come from
``grip_env.planning.features`` (its array form, so the table is built in one go).

One source for the grasping parameters: the ``params`` argument when given, else
``config.grasp``. Both may be given only when they agree (a ``config`` whose ``grasp`` differs
from ``params`` raises ``ValueError``), so no table is planned with one mu and labelled with
another.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from grip_env.columns import CANDIDATE_COLUMNS
from grip_env.config import Config
from grip_env.objects import PlanarObject
from grip_env.objects.meshes import execution_height_mm
from grip_env.params import GraspParams
from grip_env.perception.regions import Regions
from grip_env.planning.barrett import Configurations, ReachTest, configurations
from grip_env.planning.features import OUTPUT_NAMES, features_from_arrays
from grip_env.planning.finger import executable
from grip_env.planning.grasps import synthesize_grasps
from grip_env.portable_process import portable

_FINGERS = ("1", "2", "3")


@portable
def candidates(
    obj: PlanarObject,
    params: GraspParams | None = None,
    config: Config | None = None,
    regions: Regions | None = None,
    height_mm: float | None = None,
) -> pd.DataFrame:
    """Every feasible Barrett grip of ``obj`` with its descriptors and twelve features.

    Args:
        obj: the object as the planner sees it (polygon, mask or perceived contour).
        params: parameters of the quality measures (and of friction-dependent synthesis);
            ``config.grasp`` when None.
        config: synthesis and perception settings (defaults when None). Its ``grasp`` must
            equal ``params`` when both are given.
        regions: grasping regions to plan on; found from ``obj`` with ``config.perception`` when
            None.
        height_mm: height of the body the grips are executed on (the reach test); when None,
            ``obj``'s (``grip_env.objects.meshes.execution_height_mm``).

    Returns:
        A DataFrame with exactly ``CANDIDATE_COLUMNS``, one row per configuration, sorted by Q_C
        ascending (best first), index 0..n-1. ``grip_id`` is ``"{object_id}/{grasp_id}/{thumb}"``
        where ``thumb`` is the grasp contact (0-2) the thumb takes. No feasible grip gives an
        empty table with the same columns. The same bits whatever was imported first
        (:mod:`grip_env.portable_process`).
    """
    if not isinstance(obj, PlanarObject):
        raise ValueError(f"obj must be a PlanarObject, got {type(obj).__name__}")
    config, params = _settings(params, config)
    if regions is None:
        from grip_env.perception.regions import find_regions

        regions = find_regions(obj, config.perception, params)
    grasps = synthesize_grasps(regions, obj, params, config.synthesis)
    if height_mm is None:
        height_mm = execution_height_mm(obj, config.objects)
    confs = configurations(grasps, obj, params, config.synthesis,
                           _executable_test(config, height_mm))
    columns = descriptor_columns(obj, confs)
    if len(columns["hand_x"]):
        features = features_from_arrays(columns, params)
    else:
        features = np.zeros((0, len(OUTPUT_NAMES)))
    columns.update(zip(OUTPUT_NAMES, features.T, strict=True))
    order = np.argsort(columns["Q_C"], kind="stable")
    return pd.DataFrame({name: columns[name][order] for name in CANDIDATE_COLUMNS})


def _executable_test(config: Config, height_mm: float | None = None) -> ReachTest:
    """Whether the hand can put the three pads of (n, 3) finger reaches in one plane of the object.

    The executor plans every contact in that one plane (``finger.planar_contacts``);
    a configuration it cannot reach there is not a candidate, so what is planned is executed.
    The thumb search runs this test (``barrett.configurations``), so a grasp whose best direction
    the hand cannot execute keeps its best one that it can. ``height_mm`` is the executed
    body's height (``objects.thickness_mm`` when None).
    """
    sim = config.sim
    height = config.objects.thickness_mm if height_mm is None else height_mm

    def test(reaches: np.ndarray) -> np.ndarray:
        return executable(reaches, height, sim.contact_plane_rise_mm,
                          sim.fingertip_clearance_mm, sim.palm_clearance_mm, sim.preshape_gap_mm)

    return test


def _settings(params: GraspParams | None, config: Config | None) -> tuple[Config, GraspParams]:
    """The config and the grasping parameters a call plans with (see the module docstring)."""
    if params is not None and not isinstance(params, GraspParams):
        raise ValueError(f"params must be GraspParams, got {type(params).__name__}")
    if config is not None and not isinstance(config, Config):
        raise ValueError(f"config must be a Config, got {type(config).__name__}")
    if config is None:
        config = Config() if params is None else Config(grasp=params)
    elif params is not None and params != config.grasp:
        raise ValueError(f"params {params!r} differ from config.grasp {config.grasp!r}; "
                         "give one of them")
    return config, config.grasp


def descriptor_columns(obj: PlanarObject, confs: Configurations) -> dict[str, np.ndarray]:
    """Identity and descriptor columns (no features) of ``confs`` as 1-D arrays."""
    n = len(confs)
    ends_a, ends_b = confs.region_a, confs.region_b
    columns: dict[str, np.ndarray] = {
        "object_id": np.full(n, obj.name, dtype=object),
        "grasp_id": confs.grasp.astype(np.int64),
        "grip_id": np.array([f"{obj.name}/{g}/{t}" for g, t in zip(confs.grasp, confs.thumb,
                                                                    strict=True)], dtype=object),
        "two_finger": confs.two_finger.astype(bool),
    }
    for prefix, values in (("p", confs.contacts), ("n", confs.normals), ("f", confs.forces)):
        for i, finger in enumerate(_FINGERS):
            columns[f"{prefix}{finger}_x"] = values[:, i, 0]
            columns[f"{prefix}{finger}_y"] = values[:, i, 1]
    for i, finger in enumerate(_FINGERS):
        for end, values in (("a", ends_a), ("b", ends_b)):
            columns[f"r{finger}{end}_x"] = values[:, i, 0]
            columns[f"r{finger}{end}_y"] = values[:, i, 1]
    for i, finger in enumerate(_FINGERS):
        columns[f"rho{finger}"] = confs.rho[:, i]
    grasp_focus = confs.grasp_focus
    columns.update({
        "cg_x": grasp_focus[:, 0], "cg_y": grasp_focus[:, 1],
        "cc_x": confs.focus[:, 0], "cc_y": confs.focus[:, 1],
        "e1": confs.extensions[:, 0], "e2": confs.extensions[:, 1], "e3": confs.extensions[:, 2],
        "spread": confs.spread, "hand_x": confs.palm[:, 0], "hand_y": confs.palm[:, 1],
        "hand_yaw": confs.yaw,
    })
    for name, value in obj.descriptors().items():
        columns[name] = np.full(n, value)
    return columns

