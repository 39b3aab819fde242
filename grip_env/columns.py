"""Column names of the candidate and dataset tables (DESIGN's contract), in table order."""

from __future__ import annotations


def _xy(prefix: str, names: tuple[str, ...]) -> tuple[str, ...]:
    return tuple(f"{prefix}{n}_{axis}" for n in names for axis in ("x", "y"))


IDENTITY = ("object_id", "grasp_id", "grip_id", "two_finger")
CONTACTS = _xy("p", ("1", "2", "3"))
NORMALS = _xy("n", ("1", "2", "3"))
FORCES = _xy("f", ("1", "2", "3"))
REGIONS = _xy("r", ("1a", "1b", "2a", "2b", "3a", "3b"))
CURVATURES = ("rho1", "rho2", "rho3")
FOCI = ("cg_x", "cg_y", "cc_x", "cc_y")
HAND = ("e1", "e2", "e3", "spread", "hand_x", "hand_y", "hand_yaw")
OBJECT = ("area", "centroid_x", "centroid_y", "semi_major", "semi_minor")
#: The twelve features by group: shared (S), of the ideal grasp (G), of the hand (C).
SHARED_FEATURES = ("S1", "S2", "S3", "S4")
GRASP_FEATURES = ("G1", "G2")
HAND_FEATURES = ("C1", "C2", "C3", "C4", "C5", "C6")
FEATURES = SHARED_FEATURES + GRASP_FEATURES + HAND_FEATURES
INDEXES = ("Q_G", "Q_C")
OUTCOMES = ("trials", "successes", "success_rate", "success")
#: Graded outcome: the highest disturbance held per trial, mean and spread over trials, in g (an
#: acceleration of the object in multiples of gravity's 9.81 m/s², not grams).
ROBUSTNESS = ("robustness_mean", "robustness_std")
#: Per-trial outcomes by trial index k = 0..T-1 (``trial_columns(T)``, after ROBUSTNESS): whether
#: trial k held the reference level, and the highest level it held (g). Trial k of every grip of
#: an object met the same draw (friction, mass, pose noise). Datasets made before these columns
#: lack them.
TRIAL_SUCCESS_PREFIX = "trial_success_"
TRIAL_ROBUSTNESS_PREFIX = "trial_robustness_"


def trial_success_columns(trials: int) -> tuple[str, ...]:
    """``trial_success_0`` .. ``trial_success_{trials-1}``."""
    return tuple(f"{TRIAL_SUCCESS_PREFIX}{k}" for k in range(trials))


def trial_robustness_columns(trials: int) -> tuple[str, ...]:
    """``trial_robustness_0`` .. ``trial_robustness_{trials-1}``."""
    return tuple(f"{TRIAL_ROBUSTNESS_PREFIX}{k}" for k in range(trials))


def trial_columns(trials: int) -> tuple[str, ...]:
    """The per-trial columns of a dataset at ``trials`` trials a grip, in table order: every
    trial's success, then every trial's robustness."""
    return trial_success_columns(trials) + trial_robustness_columns(trials)

DESCRIPTORS = CONTACTS + NORMALS + FORCES + REGIONS + CURVATURES + FOCI + HAND + OBJECT
CANDIDATE_COLUMNS = IDENTITY + DESCRIPTORS + FEATURES + INDEXES
DATASET_COLUMNS = CANDIDATE_COLUMNS + OUTCOMES + ROBUSTNESS

#: Objects table (``objects.parquet``), beside its contour and descriptors: the object's family
#: (``grip_env.objects.family``) and, for a mesh object, its source mesh and resting pose
#: (``grip_env.objects.meshes.MeshPose``; empty for other objects).
FAMILY = "family"
MESH_POSE = ("mesh_file", "mesh_scale", "mesh_com_mm", "mesh_position_mm", "mesh_orientation",
             "mesh_height_mm")
#: Contours of the objects table (``objects.parquet``), each a list of [x, y] mm: the true
#: object, the body the simulator builds, and the one the grips were planned on when that is
#: the top-down render's segmented contour (``perception.source: render``; empty otherwise).
OBJECT_CONTOURS = ("contour", "sim_contour", "perceived_contour")
