"""Reaching a Ray cluster: RAY_ADDRESS is honoured (study and calibrate have no --address), and
configs/large.yaml is a valid config sized for one."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from grip_env.config import DEFAULT_CONFIG_PATH, load_config
from grip_env.dataset import backends

LARGE = DEFAULT_CONFIG_PATH.parent / "large.yaml"
ROOT = DEFAULT_CONFIG_PATH.parents[1]


class FakeRay:
    """Records what ``ray.init`` was called with, refusing num_cpus on a cluster as Ray does."""

    def __init__(self) -> None:
        self.calls: list[dict[str, Any]] = []

    def init(self, **kwargs: Any) -> None:
        if kwargs.get("address") is not None and "num_cpus" in kwargs:
            raise ValueError("When connecting to an existing cluster, num_cpus must not be given")
        self.calls.append(kwargs)


def test_an_explicit_address_wins_over_ray_address(monkeypatch):
    monkeypatch.setenv("RAY_ADDRESS", "10.0.0.1:6379")
    assert backends.ray_address("ray://head:10001") == "ray://head:10001"
    assert backends.ray_address(None) == "10.0.0.1:6379"
    monkeypatch.setenv("RAY_ADDRESS", "")
    assert backends.ray_address(None) is None
    monkeypatch.delenv("RAY_ADDRESS")
    assert backends.ray_address(None) is None


def test_ray_address_joins_the_cluster_without_claiming_cpus(monkeypatch):
    fake = FakeRay()
    monkeypatch.setenv("RAY_ADDRESS", "10.0.0.1:6379")
    backends._start_ray(fake, 2, None)
    assert fake.calls[-1]["address"] == "10.0.0.1:6379" and "num_cpus" not in fake.calls[-1]
    monkeypatch.delenv("RAY_ADDRESS")
    backends._start_ray(fake, 3, None)
    assert fake.calls[-1]["num_cpus"] == 3 and "address" not in fake.calls[-1]


def test_a_refused_cluster_is_a_one_line_error_naming_it(monkeypatch):
    class Refusing(FakeRay):
        def init(self, **kwargs: Any) -> None:
            raise ConnectionError("could not find any running Ray instance")

    monkeypatch.setenv("RAY_ADDRESS", "10.0.0.9:6379")
    with pytest.raises(ValueError, match=r"cannot start Ray on 10\.0\.0\.9:6379"):
        backends._start_ray(Refusing(), 2, None)


def test_large_config_loads_and_is_sized_for_a_cluster():
    config = load_config(LARGE)
    assert config.dataset.backend == "ray"
    assert config.objects.procedural_count >= 1000  # thousands of objects
    assert config.dataset.trials >= 1 and config.dataset.max_grips_per_object >= 1
    # only the sizes differ from the defaults: the physics is the default study's
    default = load_config(DEFAULT_CONFIG_PATH)
    assert (config.grasp, config.sim, config.uncertainty) == (
        default.grasp, default.sim, default.uncertainty)


def test_cluster_docs_name_what_they_run():
    text = (ROOT / "docs" / "cluster.md").read_text()
    for needed in ("ray start --head", "--address=", "RAY_ADDRESS", "configs/large.yaml",
                   "grip-env generate", "grip-env study", "bench_cluster"):
        assert needed in text, needed
    assert Path(ROOT / "tests" / "benchmarks" / "bench_cluster.py").is_file()


#: Runs the CLI with ``ray`` unimportable: a finder at the head of sys.meta_path refuses it, as
#: Python does for a package that is not installed.
_WITHOUT_RAY = """
import sys
from importlib.abc import MetaPathFinder

class NoRay(MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name == "ray" or name.startswith("ray."):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None

sys.meta_path.insert(0, NoRay())
from grip_env.cli import main
sys.argv = ["grip-env", *sys.argv[1:]]
main()
"""


def test_backend_ray_without_ray_is_refused_before_anything_is_written(tmp_path):
    import subprocess
    import sys

    out = tmp_path / "g"
    done = subprocess.run(
        [sys.executable, "-c", _WITHOUT_RAY, "generate", "--out", str(out), "--objects", "1",
         "--trials", "1", "--backend", "ray"],
        capture_output=True, text=True, timeout=120, cwd=ROOT,
    )
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr.strip().splitlines() == [
        "error: backend 'ray' needs Ray: pip install 'grip-env[cluster]'"], done.stderr
    assert not out.exists()
