"""Typed, validated configuration: one section per part of the pipeline, read from YAML.

The models below are the one source of every default: ``load_config()`` with no path is exactly
``Config()``, and ``configs/default.yaml`` (the main job's file) is tested equal to it field by
field. ``load_config(path)`` reads a YAML file with a safe loader; unknown keys, out-of-range
values, files above ``MAX_CONFIG_BYTES`` and nesting deeper than Python can follow raise
``ValueError`` naming the offending key. Every numeric setting is bounded by what is physically
and computationally sensible (a timestep, a friction, an object size);
:func:`check_contour_budget` bounds what depends on an object and a setting together.
"""

from __future__ import annotations

import difflib
from pathlib import Path
from typing import Annotated, Any, Literal, get_args

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from grip_env.hand_geometry import FINGER_WIDTH_MM
from grip_env.params import GraspParams

DEFAULT_CONFIG_PATH = Path(__file__).resolve().parents[1] / "configs" / "default.yaml"
"""The main job's YAML in a source checkout (absent from a wheel: ``load_config()`` needs none)."""

MAX_CONFIG_BYTES = 1_000_000
"""Largest config file read (a config is a few kB)."""
MAX_CONTOUR_POINTS = 100_000
"""Most points a contour may be resampled into (perimeter / ``contour_spacing_mm``)."""
MAX_OBJECT_VERTICES = 5_000
"""Most polygon vertices an object may have (its size, not its vertex count, matters here)."""
MAX_OBJECT_SIZE_MM = 2_000.0
"""Largest object extent: the open hand spans about 0.3 m; a 2 m part is not a grasp problem."""
MAX_IMAGE_PIXELS = 4096 * 4096
"""Largest object image read (as ``perception.resolution_px`` at most 4096)."""
MAX_RENDER_SIDE_PX = 8192
"""Largest rendered image side (``perception.resolution_px * supersample``)."""
MAX_SEED = 2**32 - 1
"""Largest seed: scikit-learn and Stable-Baselines3 take 32-bit seeds."""

Friction = Annotated[float, Field(ge=0.0, le=3.0)]
ObjectSize = Annotated[float, Field(ge=5.0, le=1000.0)]


class _Section(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)


def _ordered(name: str, pair: tuple[float, float]) -> None:
    if pair[0] > pair[1]:
        raise ValueError(f"{name} must be (low, high) with low <= high, got {pair}")


class ObjectsConfig(_Section):
    """Which objects a job runs on."""

    set: str = Field("default", description="named object set, or 'procedural'")
    procedural_count: int = Field(44, ge=0, le=1_000_000, description="extra procedural objects")
    procedural_size_mm: tuple[ObjectSize, ObjectSize] = Field(
        (50.0, 150.0), description="size range across (5..1000 mm)"
    )
    thickness_mm: float = Field(30.0, gt=0.0, le=500.0, description="extrusion height")
    sim_tolerance_mm: float = Field(
        0.5, ge=0.0, le=10.0,
        description="largest distance between an object's contour and its simulated body",
    )
    density_kg_m3: float = Field(
        500.0, ge=10.0, le=20_000.0, description="density for W = 1 (household object)"
    )
    mesh_count: int = Field(
        18, ge=0, le=10_000,
        description="extra mesh objects: pybullet_data household models, then random_urdfs",
    )
    mesh_size_mm: tuple[ObjectSize, ObjectSize] = Field(
        (80.0, 150.0), description="range of a mesh's longest bounding-box side (mm)"
    )
    execute_on: Literal["extrusion", "mesh"] = Field(
        "extrusion", description="body a mesh object's trials run on: its extruded silhouette "
        "or the mesh itself",
    )

    @model_validator(mode="after")
    def _sizes_ordered(self) -> ObjectsConfig:
        _ordered("procedural_size_mm", self.procedural_size_mm)
        _ordered("mesh_size_mm", self.mesh_size_mm)
        return self


class PerceptionConfig(_Section):
    """Top-down rendering, segmentation, curvature and region cutting."""

    source: Literal["polygon", "render"] = Field(
        "render", description="contour the grips plan on: the render's, or the true polygon"
    )
    resolution_px: int = Field(256, ge=32, le=4096, description="rendered image side (pixels)")
    supersample: int = Field(
        4, ge=1, le=16, description="anti-aliasing: light samples per pixel side (1: point-sampled)"
    )
    mm_per_px: float = Field(1.0, gt=0.0, le=20.0, description="rendered image scale")
    pixel_noise: float = Field(0.0, ge=0.0, le=1.0, description="grey-level noise std")
    contour_spacing_mm: float = Field(1.0, ge=0.1, le=20.0, description="contour resampling step")
    curvature_sigma_mm: float = Field(2.0, gt=0.0, le=50.0, description="curvature smoothing scale")
    max_turn_rad: float = Field(0.35, gt=0.0, le=3.2, description="max turn in a region")
    curvature_jump: float = Field(0.08, gt=0.0, le=10.0, description="curvature step (1/mm)")
    min_region_mm: float = Field(12.0, gt=0.0, le=500.0, description="shortest region for a finger")

    @model_validator(mode="after")
    def _render_size(self) -> PerceptionConfig:
        side = self.resolution_px * self.supersample
        if side > MAX_RENDER_SIDE_PX:
            raise ValueError(
                f"resolution_px * supersample = {side} renders more than {MAX_RENDER_SIDE_PX} px "
                "a side: lower supersample"
            )
        return self


class SynthesisConfig(_Section):
    """Grasp synthesis and Barrett configuration search."""

    contacts_per_region: int = Field(5, ge=1, le=50, description="candidate contacts per region")
    max_grasps: int = Field(200, ge=1, le=100_000, description="keep the best grasps by Q_G")
    thumb_search_steps: int = Field(61, ge=3, le=10_000, description="thumb directions tried")
    min_extension_mm: float = Field(15.0, ge=0.0, le=500.0, description="shortest finger reach")
    max_extension_mm: float = Field(160.0, gt=0.0, le=1000.0, description="longest finger reach")
    max_spread_rad: float = Field(1.5, gt=0.0, le=3.2, description="largest usable spread")
    finger_width_mm: float = Field(
        FINGER_WIDTH_MM, gt=0.0, le=100.0, description="finger width (the URDF's)"
    )
    focus_margin_mm: float = Field(
        1.0, ge=0.0, le=50.0,
        description="least depth of the force focus in front of every contact (a camera pixel)",
    )
    frictional_closure: bool = Field(
        False,
        description="three-finger grasps need force closure with friction mu only, so an "
                    "antipodal pair inside its friction cones plus a third contact (a cross's "
                    "arm and its tip) is kept; off, their normals must positively span the plane "
                    "(the standard dataset's planner)",
    )


#: The synthesis defaults, shared by every planner that is given no config.
DEFAULT_SYNTHESIS = SynthesisConfig()


#: The physics engines a trial may run in (``grip_env.sim.engine``); the first is the default.
EngineName = Literal["pybullet", "mujoco"]
ENGINES: tuple[str, ...] = get_args(EngineName)
DEFAULT_ENGINE = ENGINES[0]


class SimConfig(_Section):
    """Simulated execution of one grip (figures and their sources: BENCHMARKS.md, "Simulator")."""

    engine: EngineName = Field(
        DEFAULT_ENGINE,
        description="physics engine of the trials (mujoco: pip install \"grip-env[mujoco]\")",
    )
    timestep: float = Field(1.0 / 240.0, ge=1e-4, le=0.02, description="physics step (s)")
    solver_iterations: int = Field(
        150, ge=1, le=1000, description="constraint solver iterations (chosen by convergence)"
    )
    finger_force_n: float = Field(15.0, gt=0.0, le=200.0, description="fingertip force")
    finger_friction: float = Field(1.0, gt=0.0, le=3.0, description="finger pad lateral friction")
    pad_torsion_mm: float = Field(
        2.0, ge=0.0, le=50.0,
        description="pad torsional arm: a contact resists mu * N * this of twist (Hertzian, "
                    "(3 pi / 16) a at the held squeeze)",
    )
    pad_stiffness_n_per_m: float = Field(
        22_600.0, gt=0.0, le=1e7,
        description="rubber pad's contact stiffness (Hertz, 3 MPa rubber, 8 mm tip, at 15 N)",
    )
    pad_damping_n_s_per_m: float = Field(
        8.5, ge=0.0, le=1e5,
        description="rubber pad's contact damping (loss factor 0.2 with an 80 g object)",
    )
    close_speed_rad_s: float = Field(
        1.0, gt=0.0, le=10.0,
        description="finger closing speed: the worm gear keeps the impact's extra squeeze",
    )
    lift_height_mm: float = Field(60.0, gt=0.0, le=1000.0, description="lift distance")
    lift_time_s: float = Field(0.25, gt=0.0, le=10.0, description="lift duration")
    hold_time_s: float = Field(0.15, ge=0.0, le=10.0, description="hold after the lift")
    hold_tolerance_mm: float = Field(
        5.0, gt=0.0, le=500.0, description="drift in the palm frame still held"
    )
    hold_rotation_deg: float = Field(
        10.0, gt=0.0, le=180.0, description="rotation in the palm frame still held"
    )
    ramp_levels_g: tuple[float, float] = Field(
        (2.0, 128.0), description="disturbance ramp: first and last level (g)"
    )
    ramp_ratio: float = Field(
        2.0**0.25, gt=1.0, le=4.0, description="ratio between ramp levels"
    )
    ramp_fine_from_g: float = Field(
        16.0, gt=0.0,
        description="levels double from the first up to this one (within ramp_levels_g), then "
                    "rise by ramp_ratio",
    )
    ramp_steps_per_level: int = Field(
        3, ge=1, le=1000,
        description="steps each level is held at least, and the window in which it must settle",
    )
    ramp_max_steps_per_level: int = Field(
        60, ge=1, le=10_000,
        description="steps a level is held at most while the object still moves (then held)",
    )
    ramp_directions: Literal["planar", "spatial"] = Field(
        "planar", description="ramped disturbances: in the grip's plane, or also along its normal"
    )
    reference_level_g: float = Field(
        64.0, gt=0.0, le=1000.0, description="success: holds this disturbance level"
    )
    fingertip_clearance_mm: float = Field(
        4.0, ge=0.0, le=100.0, description="lowest finger point above the table while closing"
    )
    contact_plane_rise_mm: float = Field(
        8.0, ge=0.0, le=100.0,
        description="contact plane may rise this far above mid-thickness (curled tips' backs)",
    )
    palm_clearance_mm: float = Field(
        5.0, ge=0.0, le=100.0, description="palm above the object's top face"
    )
    preshape_gap_mm: float = Field(
        12.0, ge=0.0, le=100.0, description="pre-shape opening beyond contact"
    )
    max_close_steps: int = Field(90, ge=1, le=10_000, description="step cap while closing")

    @model_validator(mode="after")
    def _ramp_ordered(self) -> SimConfig:
        _ordered("ramp_levels_g", self.ramp_levels_g)
        if self.ramp_levels_g[0] <= 0:
            raise ValueError(f"ramp_levels_g must be positive, got {self.ramp_levels_g}")
        return self


class UncertaintyConfig(_Section):
    """Execution noise, each drawn from a seeded generator per trial."""

    position_std_mm: float = Field(2.0, ge=0.0, le=50.0, description="palm position error std")
    yaw_std_rad: float = Field(0.02, ge=0.0, le=1.0, description="palm orientation error std")
    friction_range: tuple[Friction, Friction] = Field(
        (0.4, 0.9), description="true pad-object friction drawn in (0..3)"
    )
    mass_rel_std: float = Field(0.2, ge=0.0, le=2.0, description="object mass relative std")
    draws: Literal["common", "per_grip"] = Field(
        "common",
        description="trial k of every grip of an object shares one draw (common), or each grip "
                    "draws its own (per_grip, before label model 2026.12-crn)",
    )
    stratified: bool = Field(
        False,
        description="spread friction and mass over their ranges across each block of "
                    "dataset.trials trials (Latin hypercube) instead of sampling independently",
    )
    stratified_palm: bool = Field(
        False,
        description="spread the palm's two offsets and its yaw error over their distributions "
                    "across each block of dataset.trials trials (Latin hypercube)",
    )
    perceived_contour: bool = Field(False, description="plan on the perceived contour")

    @model_validator(mode="after")
    def _friction_ordered(self) -> UncertaintyConfig:
        _ordered("friction_range", self.friction_range)
        return self


class DatasetConfig(_Section):
    """Dataset generation."""

    trials: int = Field(5, ge=1, le=1000, description="simulated trials per grip")
    seed: int = Field(0, ge=0, le=MAX_SEED, description="run seed")
    workers: int = Field(2, ge=1, le=1024, description="parallel workers")
    backend: Literal["process", "ray"] = Field("process", description="parallel backend")
    max_grips_per_object: int = Field(30, ge=1, le=10_000, description="grips kept per object")
    sampling: Literal["stratified", "best", "uniform"] = Field(
        "stratified",
        description="which grips an object keeps: stratified (a quarter best by Q_C, the rest "
        "one seeded pick per equal-rank stratum of the Q_C ranking), best (lowest Q_C) or "
        "uniform (a seeded sample)",
    )


class LearningConfig(_Section):
    """Classifiers, evaluation and ablation."""

    models: tuple[str, ...] = Field(
        ("svm", "mlp_sklearn", "knn", "logreg", "hgb", "rank_qc", "rank_qg", "random"),
        min_length=1,
        description="models trained and compared (the registry's mlp_torch too, at about three "
        "times mlp_sklearn's cost a fit)",
    )
    regressors: tuple[str, ...] = Field(
        ("svr", "ridge", "hgb", "rank_qc", "rank_qg", "random"),
        min_length=1,
        description="regressors of robustness_mean trained and compared (the registry's "
        "mlp_sklearn and mlp_torch too; on the standard dataset mlp_sklearn cost seven times hgb a "
        "fit and ranked worse)",
    )
    rankers: tuple[str, ...] = Field(
        ("lambdarank", "rank_qc", "rank_qg", "random"),
        min_length=1,
        description="learning-to-rank models (a group: one object's grips) trained and compared",
    )
    image_models: tuple[str, ...] = Field(
        ("cnn", "cnn_measures"),
        description="convolutional models of the grip image (cnn) and of the image with the "
        "twelve measures (cnn_measures) the study's image stage sets beside ablation_model; "
        "empty: no image stage",
    )
    seeds: int = Field(
        4, ge=1, le=100,
        description="training seeds (seed, seed+1, ...) of every learner scored on the held-out "
        "objects",
    )
    ablation_model: str = Field(
        "hgb", min_length=1,
        description="classifier the feature ablation and the power curve cross-validate",
    )
    folds: int = Field(5, ge=2, le=100, description="grouped CV folds")
    repeats: int = Field(2, ge=1, le=100, description="CV repeats over seeds")
    workers: int = Field(
        2, ge=1, le=1024,
        description="processes the cross-validation folds are fitted in (one thread each; the "
        "results do not depend on it)",
    )
    seed: int = Field(0, ge=0, le=MAX_SEED, description="learning seed")
    test_fraction: float = Field(0.25, gt=0.0, lt=1.0, description="held-out object fraction")


class SelectorConfig(_Section):
    """RL selector training."""

    timesteps: int = Field(20_000, ge=1, le=100_000_000, description="training timesteps")
    max_candidates: int = Field(64, ge=2, le=4096, description="K, candidates per observation")
    max_attempts: int = Field(1, ge=1, le=100, description="attempts per episode")
    retry_attempts: int = Field(
        3, ge=1, le=100,
        description="the study's retry selector: attempts an episode, replaying one trial index "
        "(1: none); trained only on a dataset that records every trial's outcome",
    )
    reward: Literal["success", "expected_success", "robustness"] = Field(
        "success", description="reward of a pick: success (0/1), expected_success (the grip's "
        "recorded success rate: a variance-reduction baseline) or robustness / reference level"
    )
    context: Literal["none", "pool", "attention"] = Field(
        "none", description="how the set policy's scorer sees the other candidates: not at all, "
        "their pooled embedding, or self-attention"
    )
    seed: int = Field(0, ge=0, le=MAX_SEED, description="training seed")
    seeds: int = Field(4, ge=1, le=100, description="training runs, seeds seed, seed+1, ...")
    workers: int = Field(
        2, ge=1, le=1024,
        description="processes the training runs share (each on one thread; the runs do not "
        "depend on it)",
    )
    n_envs: int = Field(4, ge=1, le=256, description="environment copies stepped together")
    rollout_steps: int = Field(
        512, ge=16, le=1_000_000, description="PPO rollout, steps over all environment copies"
    )
    batch_size: int = Field(128, ge=2, le=1_000_000, description="PPO minibatch size")
    n_epochs: int = Field(5, ge=1, le=1000, description="PPO epochs per rollout")
    learning_rate: float = Field(1e-3, gt=0.0, le=1.0, description="PPO learning rate")
    gamma: float = Field(0.99, ge=0.0, le=1.0, description="PPO discount factor")
    ent_coef: float = Field(0.01, ge=0.0, le=1.0, description="PPO entropy coefficient")

    @model_validator(mode="after")
    def _attempts_within_candidates(self) -> SelectorConfig:
        for name in ("max_attempts", "retry_attempts"):
            if getattr(self, name) > self.max_candidates:
                raise ValueError(f"{name} {getattr(self, name)} exceeds max_candidates "
                                 f"{self.max_candidates}: an episode shows no more candidates")
        return self


class Config(_Section):
    """The whole configuration; every section has defaults."""

    grasp: GraspParams = GraspParams()
    objects: ObjectsConfig = ObjectsConfig()
    perception: PerceptionConfig = PerceptionConfig()
    synthesis: SynthesisConfig = SynthesisConfig()
    sim: SimConfig = SimConfig()
    uncertainty: UncertaintyConfig = UncertaintyConfig()
    dataset: DatasetConfig = DatasetConfig()
    learning: LearningConfig = LearningConfig()
    selector: SelectorConfig = SelectorConfig()

    def override(self, **sections: dict[str, Any]) -> Config:
        """A copy with some fields replaced, e.g. ``override(dataset={"trials": 3})``."""
        data = self.model_dump()
        for name, fields in sections.items():
            if name not in data:
                raise ValueError(f"unknown config section {name!r}")
            data[name] = {**data[name], **fields}
        return config_from_dict(data)


def check_setting(section: str, key: str, value: Any, label: str | None = None) -> Any:
    """``value`` validated as config key ``section.key`` is, e.g. a CLI flag that overrides it.

    Returns the validated value; a bad one raises ``ValueError`` naming ``label`` (default
    ``section.key``), the bound and the value, so ``--workers 10**12`` is refused like
    ``dataset.workers: 10**12`` in a file.
    """
    model = type(getattr(Config(), section, None))
    if model is type(None) or key not in model.model_fields:
        raise ValueError(f"unknown config key {section}.{key}")
    try:
        return getattr(model.model_validate({key: value}), key)
    except ValidationError as exc:
        problems = "; ".join(_problem(err).removeprefix(f"{key}: ") for err in exc.errors())
        raise ValueError(f"{label or f'{section}.{key}'}: {problems}") from None


def config_from_dict(data: dict[str, Any]) -> Config:
    """Validate a nested dict into a ``Config``; errors name the offending key."""
    try:
        return Config.model_validate(data)
    except ValidationError as exc:
        problems = "; ".join(_problem(err) for err in exc.errors())
        raise ValueError(f"invalid config: {problems}") from None


def _problem(err: Any) -> str:
    """``section.key: message (got value)`` for one pydantic error; an unknown key names the
    nearest known one."""
    where = ".".join(str(p) for p in err["loc"])
    if err["type"] == "extra_forbidden":
        return f"{where}: unknown key{_nearest(err['loc'])}"
    message = err["msg"].removeprefix("Value error, ")
    value = err.get("input")
    if isinstance(value, dict) or err["type"] == "missing":
        return f"{where}: {message}"
    shown = repr(value)
    return f"{where}: {message} (got {shown if len(shown) <= 60 else shown[:57] + '...'})"


def _nearest(location: tuple[Any, ...]) -> str:
    """``; did you mean section.key?`` for a misspelled key, or nothing."""
    *section, key = (str(part) for part in location)
    if section:
        model = Config.model_fields.get(section[0])
        known = list(model.annotation.model_fields) if model is not None else []
    else:
        known = list(Config.model_fields)
    close = difflib.get_close_matches(key, known, n=1, cutoff=0.6)
    return f"; did you mean {'.'.join([*section, close[0]])}?" if close else ""


def load_config(path: str | Path | None = None) -> Config:
    """Read a YAML config; with no path, the defaults ``Config()`` (no file is read)."""
    if path is None:
        return Config()
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"config file not found: {path}")
    if path.stat().st_size > MAX_CONFIG_BYTES:
        raise ValueError(f"config {path} is larger than {MAX_CONFIG_BYTES} bytes")
    try:
        data = yaml.safe_load(path.read_text()) or {}
    except yaml.YAMLError as exc:
        raise ValueError(f"config {path} is not valid YAML: {_one_line(exc)}") from None
    except RecursionError:
        raise ValueError(f"config {path} is nested too deeply to be a config") from None
    except UnicodeDecodeError as exc:
        raise ValueError(f"config {path} is not UTF-8 text: {exc.reason}") from None
    if not isinstance(data, dict):
        raise ValueError(f"config {path} must be a mapping of sections, got {type(data).__name__}")
    try:
        return config_from_dict(data)
    except RecursionError:
        raise ValueError(f"config {path} is nested too deeply to be a config") from None
    except ValueError as exc:
        raise ValueError(f"config {path}: {exc}") from None


def check_contour_budget(
    name: str, vertices: int, perimeter_mm: float, extent_mm: float, perception: PerceptionConfig
) -> None:
    """Refuse an object too large, too detailed or too finely sampled to process.

    Args:
        name: the object's name, for the message.
        vertices: its polygon's vertex count.
        perimeter_mm: its contour length.
        extent_mm: its largest bounding-box side.
        perception: supplies ``contour_spacing_mm``.

    Raises:
        ValueError: above ``MAX_OBJECT_VERTICES``, ``MAX_OBJECT_SIZE_MM`` or
            ``MAX_CONTOUR_POINTS`` (perimeter / spacing), naming the value and the bound.
    """
    if vertices > MAX_OBJECT_VERTICES:
        raise ValueError(
            f"object {name!r} has {vertices} vertices, more than {MAX_OBJECT_VERTICES}: "
            "simplify the polygon or use a smaller image"
        )
    if not extent_mm <= MAX_OBJECT_SIZE_MM:
        raise ValueError(
            f"object {name!r} is {extent_mm:.4g} mm across, more than {MAX_OBJECT_SIZE_MM:g} mm "
            "(check its units, or the scale of its image)"
        )
    points = perimeter_mm / perception.contour_spacing_mm
    if not points <= MAX_CONTOUR_POINTS:
        raise ValueError(
            f"object {name!r}: perception.contour_spacing_mm {perception.contour_spacing_mm:g} "
            f"would sample its {perimeter_mm:.4g} mm contour into {points:.3g} points, "
            f"more than {MAX_CONTOUR_POINTS}"
        )


def _one_line(exc: Exception) -> str:
    return " ".join(str(exc).split())


def config_reference_markdown() -> str:
    """The configuration reference table (the documentation's), generated from the fields above:
    every key with its default, the values it accepts and its description."""
    lines = ["| key | default | accepted | meaning |", "| --- | --- | --- | --- |"]
    defaults = Config()
    for section in Config.model_fields:
        values = getattr(defaults, section)
        schema = type(values).model_json_schema()["properties"]
        for name, field in type(values).model_fields.items():
            value = _show(getattr(values, name))
            accepted = _accepted(schema[name])
            lines.append(f"| `{section}.{name}` | {value} | {accepted} | "
                         f"{field.description or ''} |")
    return "\n".join(lines)


def _accepted(schema: dict[str, Any]) -> str:
    """The values a field's JSON schema accepts, in words: its range, its choices or its kind."""
    if "enum" in schema:
        return ", ".join(f"`{choice}`" for choice in schema["enum"])
    if schema.get("type") == "array":
        items = schema.get("prefixItems") or [schema.get("items", {})]
        each = _accepted(items[0])
        count = len(items) if "prefixItems" in schema else None
        shape = f"{count} values" if count else "a list"
        return f"{shape}, each {each}" if each else shape
    kind = {"integer": "integer", "number": "number", "boolean": "true or false",
            "string": "text"}.get(schema.get("type", ""), "")
    low, high = _bound(schema, "minimum", "["), _bound(schema, "maximum", "]")
    if low and high:
        return f"{kind} in {low[0]}{low[1]}, {high[1]}{high[0]}"
    if low or high:
        words = {"[": "≥", "(": ">", "]": "≤", ")": "<"}
        bracket, value = low or high
        return f"{kind} {words[bracket]} {value}"
    return kind


def _bound(schema: dict[str, Any], key: str, closed: str) -> tuple[str, str] | None:
    """A schema's ``minimum``/``maximum`` (bracket ``closed``) or exclusive one, shown."""
    if key in schema:
        return closed, _show(schema[key])
    exclusive = f"exclusive{key.capitalize()}"
    if exclusive not in schema:
        return None
    return "(" if closed == "[" else ")", _show(schema[exclusive])


def _show(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, tuple):
        return ", ".join(_show(v) for v in value)
    return str(value)
