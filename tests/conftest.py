"""Shared fixtures: a small dataset generated for real (planning, PyBullet trials, Parquet)."""

from __future__ import annotations

import grip_env  # noqa: F401  first, before numpy: it holds numpy at x86-64-v3 (portable_math)

# isort: split
import os
from pathlib import Path

import pandas as pd
import pytest
from hypothesis import settings

from grip_env.config import Config

# The shutdown and fault tests' fixtures (``config``, ``reference``) live beside their helpers.
pytest_plugins = ["generate_runs"]

# CI runs hypothesis derandomised, so a run is reproducible; locally it keeps exploring. No
# deadline in either: a shared machine's load made a 0.7 ms example take 265 ms once, and speed
# is measured by the benchmarks, never asserted by a test's timing.
settings.register_profile("ci", derandomize=True, print_blob=True, deadline=None)
settings.register_profile("local", deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "local")


@pytest.fixture(scope="session")
def generated_dataset_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The 'basic' objects plus four procedural ones, 6 grips each, 2 trials: real labels."""
    from grip_env.dataset import generate

    config = Config().override(
        objects={"set": "basic", "procedural_count": 4, "mesh_count": 0},
        dataset={"trials": 2, "max_grips_per_object": 6, "workers": 1},
    )
    return generate(config, tmp_path_factory.mktemp("generated") / "data", progress=False)


@pytest.fixture(scope="session")
def generated_grips(generated_dataset_dir: Path) -> pd.DataFrame:
    """The grips of :func:`generated_dataset_dir`, loaded."""
    from grip_env.dataset import load

    return load(generated_dataset_dir)
