"""The twelve quality measures and the two indexes (public path of
:mod:`grip_env.planning.features`, kept by the design's contract)."""

from grip_env.planning.features import (
    FEATURE_NAMES,
    INDEX_NAMES,
    OUTPUT_NAMES,
    REQUIRED_COLUMNS,
    compute_features,
    features_from_arrays,
)

__all__ = ["FEATURE_NAMES", "INDEX_NAMES", "OUTPUT_NAMES", "REQUIRED_COLUMNS", "compute_features",
           "features_from_arrays"]
