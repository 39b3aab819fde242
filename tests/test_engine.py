"""The engine seam: ``sim.engine`` picks the physics engine, PyBullet by default; bad choices are
refused in one line before anything is written."""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_runs import assert_refused
from cli_runs import cli as run

from grip_env.config import Config
from grip_env.dataset.manifest import fingerprint, run_identity
from grip_env.sim import engine
from grip_env.sim.engine import EngineUnavailable, make_world, require_engine
from grip_env.sim.world import World


def test_pybullet_is_the_default_engine_and_builds_today_s_world():
    config = Config()
    assert config.sim.engine == "pybullet"
    with make_world(config.sim) as world:
        assert type(world) is World
        assert world.timestep == config.sim.timestep
        assert world.solver_iterations == config.sim.solver_iterations


def test_an_unknown_engine_is_refused_by_name():
    with pytest.raises(ValueError, match=r"sim\.engine"):
        Config.model_validate({"sim": {"engine": "physx"}})
    with pytest.raises(ValueError, match="unknown engine 'physx'"):
        require_engine("physx")


def without_mujoco(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make ``import mujoco`` fail as it does where it is not installed (``None`` in
    ``sys.modules`` is Python's own "not importable"; the world's module is imported anew)."""
    import sys

    monkeypatch.setitem(sys.modules, "mujoco", None)
    monkeypatch.delitem(sys.modules, "grip_env.sim.mujoco_world", raising=False)


def test_an_engine_not_installed_says_how_to_install_it(monkeypatch):
    without_mujoco(monkeypatch)
    with pytest.raises(EngineUnavailable, match='pip install "grip-env\\[mujoco\\]"'):
        make_world(Config().override(sim={"engine": "mujoco"}).sim)
    with pytest.raises(ImportError):  # the simulation is real: the module cannot be imported
        import grip_env.sim.mujoco_world  # noqa: F401


def test_an_engine_that_cannot_be_loaded_says_so_and_how_to_reinstall(monkeypatch):
    import importlib

    real = importlib.import_module

    def broken(name: str, *args: object):
        if name == "grip_env.sim.mujoco_world":
            raise ImportError("libmujoco.so.4.0.1: cannot open shared object file")
        return real(name, *args)

    monkeypatch.setattr(importlib, "import_module", broken)
    with pytest.raises(EngineUnavailable, match=r"cannot be loaded .*libmujoco.*reinstall"):
        require_engine("mujoco")


@pytest.mark.parametrize("command", ["generate", "calibrate", "study"])
def test_the_cli_refuses_an_unknown_engine_and_writes_nothing(tmp_path, command):
    config = tmp_path / "physx.yaml"
    config.write_text("sim:\n  engine: physx\n")
    out = tmp_path / "out"
    assert_refused(*run(command, "--config", config, "--out", out), "sim.engine")
    assert not out.exists()


@pytest.mark.parametrize("command", ["generate", "calibrate", "study"])
def test_the_cli_refuses_a_missing_engine_in_one_line(tmp_path, monkeypatch, command):
    without_mujoco(monkeypatch)
    config = tmp_path / "mujoco.yaml"
    config.write_text("sim:\n  engine: mujoco\n")
    out = tmp_path / "out"
    assert_refused(*run(command, "--config", config, "--out", out),
                   'pip install "grip-env[mujoco]"')
    assert not out.exists()


def test_a_pybullet_run_keeps_its_identity_and_a_mujoco_run_is_another():
    default = run_identity(Config(), [])
    assert "engine" not in default["config"]["sim"]  # as every run before the seam
    mujoco = run_identity(Config().override(sim={"engine": "mujoco"}), [])
    assert mujoco["config"]["sim"]["engine"] == "mujoco"
    assert fingerprint(mujoco) != fingerprint(default)


def test_only_the_mujoco_world_and_its_frames_import_mujoco():
    import ast
    from pathlib import Path

    root = Path(engine.__file__).resolve().parents[1]
    importers = set()
    for path in root.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            if any(name.split(".")[0] == "mujoco" for name in names):
                importers.add(path.relative_to(root).as_posix())
    assert importers == {"sim/mujoco_world.py", "sim/mujoco_rendering.py"}


def test_a_manifest_records_the_engine_its_version_and_its_label_model():
    from grip_env.dataset.manifest import new_manifest
    from grip_env.label_model import LABEL_MODEL, MUJOCO_LABEL_MODEL

    default = new_manifest(Config(), [], [], "0" * 64)
    assert default["label_model"] == LABEL_MODEL
    assert default["engine"]["name"] == "pybullet" and default["engine"]["version"]
    mujoco = new_manifest(Config().override(sim={"engine": "mujoco"}), [], [], "0" * 64)
    assert mujoco["label_model"] == mujoco["identity"]["label_model"] == MUJOCO_LABEL_MODEL
    assert mujoco["engine"]["name"] == "mujoco"


def test_an_environment_refuses_an_unknown_engine():
    import gymnasium

    import grip_env.envs  # noqa: F401  (registers the environments)

    with pytest.raises(ValueError, match="unknown engine 'physx'"):
        gymnasium.make("GripSelect-v0", objects=["rectangle"], engine="physx")


@pytest.mark.slow
@pytest.mark.skipif(__import__("importlib").util.find_spec("mujoco") is None,
                    reason="mujoco not installed")
def test_an_environment_runs_live_in_mujoco():
    import gymnasium

    import grip_env.envs  # noqa: F401

    env = gymnasium.make("GripSelect-v0", objects=["rectangle"], engine="mujoco")
    assert env.unwrapped.config.sim.engine == "mujoco"
    env.reset(seed=0)
    _, reward, _, _, info = env.step(0)
    assert reward in (0.0, 1.0) and "success" in info
    env.close()


def test_a_session_stamps_the_label_model_and_version_of_its_own_engine():
    from datetime import UTC, datetime

    from grip_env.dataset.manifest import session_record
    from grip_env.label_model import LABEL_MODEL, MUJOCO_LABEL_MODEL

    start = datetime(2026, 12, 6, tzinfo=UTC)
    pybullet = session_record(start, 1.0, 1, "process", 1, 3, None)
    assert pybullet["label_model"] == LABEL_MODEL and pybullet["engine"]["name"] == "pybullet"
    mujoco = session_record(start, 1.0, 1, "process", 1, 3, None, engine="mujoco")
    assert mujoco["label_model"] == MUJOCO_LABEL_MODEL != LABEL_MODEL
    assert mujoco["engine"]["name"] == "mujoco"


def test_a_dataset_is_judged_against_the_label_model_of_its_own_engine():
    from grip_env.label_model import (
        LABEL_MODEL,
        MUJOCO_LABEL_MODEL,
        engine_of,
        label_model_warning,
    )

    mujoco = {"label_model": MUJOCO_LABEL_MODEL, "engine": {"name": "mujoco", "version": "4"}}
    assert engine_of(mujoco) == "mujoco" and label_model_warning(mujoco) is None
    mislabelled = {**mujoco, "label_model": LABEL_MODEL}
    warning = label_model_warning(mislabelled)
    assert warning and repr(LABEL_MODEL) in warning and repr(MUJOCO_LABEL_MODEL) in warning
    older = {"label_model": LABEL_MODEL, "config": {"sim": {}}}  # made before engines
    assert engine_of(older) == "pybullet" and label_model_warning(older) is None
    by_config = {"label_model": MUJOCO_LABEL_MODEL, "config": {"sim": {"engine": "mujoco"}}}
    assert label_model_warning(by_config) is None


@pytest.mark.skipif(__import__("importlib").util.find_spec("mujoco") is None,
                    reason="mujoco not installed")
def test_the_engine_version_a_manifest_records_is_the_engine_s_own():
    import re

    import mujoco

    from grip_env.dataset.manifest import engine_record

    assert engine_record("mujoco") == {"name": "mujoco", "version": mujoco.__version__}
    assert re.fullmatch(r"\d+\.\d+\.\d+", engine_record("pybullet")["version"])


@pytest.mark.slow
@pytest.mark.skipif(__import__("importlib").util.find_spec("mujoco") is None,
                    reason="mujoco not installed")
def test_generate_validate_and_calibrate_run_in_the_config_s_engine(tmp_path):
    """End to end on one object: generate labels in the config's engine (the same grips as
    PyBullet's, other outcomes), validate re-simulates them in it bit for bit, and calibrate
    runs its trials in it (about 25 s)."""
    import json

    from grip_env.dataset import load
    from grip_env.label_model import LABEL_MODEL, MUJOCO_LABEL_MODEL

    tiny = "dataset:\n  trials: 2\n  max_grips_per_object: 3\n  workers: 1\n"
    data = {}
    for name in ("pybullet", "mujoco"):
        config = tmp_path / f"{name}.yaml"
        config.write_text(f"sim:\n  engine: {name}\n{tiny}")
        code, output = run("generate", "--config", config, "--objects", "1", "--out",
                           tmp_path / name, "--no-progress")
        assert code == 0, output
        data[name] = load(tmp_path / name)
    manifest = json.loads((tmp_path / "mujoco" / "manifest.json").read_text())
    assert manifest["engine"]["name"] == "mujoco"
    assert manifest["label_model"] == MUJOCO_LABEL_MODEL != LABEL_MODEL
    outcomes = ["successes", "robustness_mean", "robustness_std"]
    grips = [c for c in data["pybullet"].columns if c not in outcomes and "trial" not in c
             and c not in ("success", "success_rate")]
    assert len(data["mujoco"]) == 3 and {"S1", "C6", "Q_C", "hand_x"} <= set(grips)
    assert data["mujoco"][grips].equals(data["pybullet"][grips])  # planning knows no engine
    assert not data["mujoco"][outcomes].equals(data["pybullet"][outcomes])
    code, output = run("validate", tmp_path / "mujoco", "--resimulate", 3, "--workers", 1)
    assert code == 0 and "label model " + MUJOCO_LABEL_MODEL in output, output
    assert "outcomes identical on 3" in output, output
    code, output = run("calibrate", "--config", tmp_path / "mujoco.yaml", "--quick",
                       "--workers", 1, "--out", tmp_path / "calibration")
    assert code == 0, output
    calibration = json.loads((tmp_path / "calibration" / "calibration.json").read_text())
    assert calibration["label_model"] == MUJOCO_LABEL_MODEL
    assert calibration["config"]["sim"]["engine"] == "mujoco"
    assert "calibration trials in MuJoCo" in (tmp_path / "calibration" /
                                              "calibration.md").read_text()


def test_a_manifest_made_before_engines_were_recorded_names_its_engine_s_version():
    """A manifest that predates the ``engine`` record (the standard dataset's did until label
    model 2026.12-hertz): the engine's version it was made with is the one its ``versions``
    recorded, and the card says so; the shipped one records its engine."""
    from grip_env.dataset.card import _engines
    from grip_env.dataset.manifest import read_manifest, recorded_engine
    from grip_env.datasets import standard_path

    manifest = read_manifest(standard_path())
    pybullet = {"name": "pybullet", "version": manifest["versions"]["pybullet"]}
    assert manifest["engine"] == pybullet == recorded_engine(manifest)
    older = {key: value for key, value in manifest.items() if key != "engine"}
    assert recorded_engine(older) == pybullet
    line = f"Labelled in pybullet {manifest['versions']['pybullet']},"
    assert line in _engines(older, standard_path(), None)
    assert line in (Path(__file__).parents[1] / "docs" / "dataset.md").read_text()
    assert recorded_engine({"engine": {"name": "mujoco", "version": "4.0.1"},
                            "versions": {"pybullet": "3.2.7"}}) == {"name": "mujoco",
                                                                    "version": "4.0.1"}
    assert recorded_engine({"config": {"sim": {"engine": "mujoco"}}}) == {"name": "mujoco",
                                                                          "version": None}
