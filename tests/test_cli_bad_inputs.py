"""Bad inputs from the command line: each ends in one ``error:`` line and exit code 2, fast.

Every case of the reliability review that used to crash (traceback), run without end, or mislead
is here; each must be refused before any heavy work (planning, physics, training) starts.
"""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path

import numpy as np
import pytest
from cli_runs import RUNNER, app, assert_refused
from cli_runs import cli as run
from PIL import Image


def read_only_dir(tmp_path: Path) -> Path:
    """A directory nothing can be written into: chmod for users, a read-only mount for root."""
    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(stat.S_IRUSR | stat.S_IXUSR)
    if os.access(folder, os.W_OK):  # root ignores modes: use a read-only file system instead
        try:
            Path("/sys/.grip-env-probe").touch()
        except OSError:
            return Path("/sys")
        pytest.skip("no read-only directory available")
    return folder


# ----------------------------------------------------------------- config files
BAD_CONFIGS = {
    "friction_huge": ("uncertainty:\n  friction_range: [1.0e308, 1.0e309]\n",
                      "uncertainty.friction_range"),
    "spacing_tiny": ("perception:\n  contour_spacing_mm: 1.0e-9\n",
                     "perception.contour_spacing_mm"),
    "timestep_tiny": ("sim:\n  timestep: 1.0e-9\n", "sim.timestep"),
    "size_huge": ("objects:\n  procedural_size_mm: [1.0e300, 1.0e301]\n",
                  "objects.procedural_size_mm"),
    "deep": ("grasp: " + "[" * 5000 + "]" * 5000 + "\n", "nested too deeply"),
    "draw_scheme": ("uncertainty:\n  draws: shared\n", "uncertainty.draws"),
    "steps_per_level": ("sim:\n  ramp_steps_per_level: 0\n", "sim.ramp_steps_per_level"),
    "longest_level": ("sim:\n  ramp_max_steps_per_level: -3\n",
                      "sim.ramp_max_steps_per_level"),
    "engine": ("sim:\n  engine: physx\n", "sim.engine"),
}


@pytest.mark.parametrize("case", sorted(BAD_CONFIGS))
def test_bad_config_values_are_refused_in_one_line(tmp_path, case):
    text, fragment = BAD_CONFIGS[case]
    config = tmp_path / "bad.yaml"
    config.write_text(text)
    out = tmp_path / "x.png"
    assert_refused(*run("show", "star", "--config", config, "--out", out), fragment)
    assert not out.exists()


# ----------------------------------------------------------------- show
def test_show_out_directory_is_refused_not_written_beside(tmp_path):
    folder = tmp_path / "figs"
    folder.mkdir()
    assert_refused(*run("show", "star", "--out", folder), "is a directory")
    assert not (tmp_path / "figs.png").exists()


def test_show_writes_exactly_where_told_or_refuses(tmp_path):
    assert_refused(*run("show", "star", "--out", tmp_path / "noext"), "must end in .png")
    assert not list(tmp_path.iterdir())
    code, output = run("show", "star", "--out", tmp_path / "star.png")
    assert code == 0, output
    assert output.strip() == f"wrote {tmp_path / 'star.png'}"
    assert (tmp_path / "star.png").read_bytes()[:4] == b"\x89PNG"


def test_show_out_on_a_read_only_file_system(tmp_path):
    assert_refused(*run("show", "star", "--out", read_only_dir(tmp_path) / "x.png"),
                   "cannot write there")


def test_show_out_under_a_file(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert_refused(*run("show", "star", "--out", blocker / "x.png"), "is a file")


def test_show_of_a_huge_square_is_refused(tmp_path):
    side = 1e9
    path = tmp_path / "huge.json"
    path.write_text(json.dumps([[0, 0], [side, 0], [side, side], [0, side]]))
    assert_refused(*run("show", path, "--out", tmp_path / "x.png"), "mm across")


def test_show_of_a_million_vertex_polygon_is_refused(tmp_path):
    angle = np.linspace(0, 2 * np.pi, 1_000_000, endpoint=False)
    path = tmp_path / "many.csv"
    np.savetxt(path, 60 * np.column_stack([np.cos(angle), np.sin(angle)]), delimiter=",",
               fmt="%.6f")
    assert_refused(*run("show", path, "--out", tmp_path / "x.png"), "1000000 vertices")


def test_show_of_an_oversized_image_is_refused_before_decoding(tmp_path):
    path = tmp_path / "big.png"
    Image.new("L", (5000, 4000)).save(path)
    assert_refused(*run("show", path, "--out", tmp_path / "x.png"), "5000 x 4000 pixels")


def comb_too_fine_to_sample(tmp_path: Path) -> tuple[Path, Path]:
    """A comb's vertex file and a config that would sample its contour into too many points:
    1.9 m teeth make a 77 m contour inside a 0.8 x 1.9 m box (within the size bound), and
    ``contour_spacing_mm: 0.1`` would cut it into 772 000 points."""
    config = tmp_path / "fine.yaml"
    config.write_text("perception:\n  contour_spacing_mm: 0.1\n")
    teeth = [[x, y] for i in range(20) for x, y in
             ((40.0 * i, 1900.0), (40.0 * i + 20, 1900.0), (40.0 * i + 20, 10.0),
              (40.0 * i + 40, 10.0))]
    path = tmp_path / "comb.json"
    path.write_text(json.dumps([[0.0, 0.0], [800.0, 0.0], *teeth[::-1]]))
    return path, config


def test_show_of_a_fine_spacing_on_a_large_object_is_refused(tmp_path):
    path, config = comb_too_fine_to_sample(tmp_path)
    assert_refused(*run("show", path, "--config", config, "--out", tmp_path / "x.png"),
                   "contour_spacing_mm 0.1")


# ----------------------------------------------------------------- train
def test_train_out_naming_an_existing_file(tmp_path):
    blocker = tmp_path / "metrics"
    blocker.write_text("")
    assert_refused(*run("train", "--data", tmp_path, "--out", blocker), "existing file")


def test_train_out_on_a_read_only_file_system(tmp_path):
    assert_refused(*run("train", "--data", tmp_path, "--out", read_only_dir(tmp_path) / "m"),
                   "cannot")


@pytest.mark.parametrize(("models", "fragment"), [
    (",", "names no model"),
    (" , ,", "names no model"),
    ("svm,nosuch", "unknown model 'nosuch'"),
    ("svm,svm", "named twice"),
])
def test_train_models_are_checked_before_the_data(tmp_path, models, fragment):
    code, output = run("train", "--data", tmp_path / "none", "--out", tmp_path / "m",
                       "--models", models)
    assert_refused(code, output, fragment)
    assert not (tmp_path / "m").exists()


def test_ablate_model_is_checked_before_the_data(tmp_path):
    assert_refused(*run("ablate", "--data", tmp_path / "none", "--out", tmp_path / "a",
                        "--model", "nosuch"), "unknown model 'nosuch'")
    assert not (tmp_path / "a").exists()


def test_select_timesteps_are_bounded_before_any_training(tmp_path):
    assert_refused(*run("select", "--data", tmp_path / "none", "--out", tmp_path / "s",
                        "--timesteps", "99999999999999999999999"), "timesteps")
    for steps in ("0", "-5"):  # below the range --help states: a usage error (one line, exit 2)
        result = RUNNER.invoke(app, ["select", "--data", str(tmp_path / "none"), "--out",
                                     str(tmp_path / "s"), "--timesteps", steps],
                               standalone_mode=False)
        message = result.exception.format_message()
        assert "'--timesteps'" in message and "greater than or equal to 1" in message
    assert not (tmp_path / "s").exists()


# ----------------------------------------------------------------- generate
@pytest.mark.parametrize(("flag", "value"), [
    ("--objects", "99999999999999999999"), ("--workers", "1000000000000"),
])
def test_generate_huge_counts_are_refused(tmp_path, flag, value):
    args = {"--objects": "1", "--workers": "1", flag: value}
    assert_refused(*run("generate", "--out", tmp_path / "g", "--trials", "1",
                        *[item for pair in args.items() for item in pair]), flag, value)


def test_generate_address_needs_the_ray_backend(tmp_path):
    assert_refused(*run("generate", "--out", tmp_path / "g", "--objects", "1",
                        "--backend", "process", "--address", "ray://host:10001"), "--address")


def test_generate_of_an_oversized_image_in_a_folder_is_refused_before_decoding(tmp_path):
    folder = tmp_path / "parts"
    folder.mkdir()
    Image.new("L", (5000, 4000)).save(folder / "big.png")
    assert_refused(*run("generate", "--out", tmp_path / "g", "--objects", folder,
                        "--mm-per-px", "0.1"), "big.png", "5000 x 4000 pixels")
    assert not (tmp_path / "g").exists()


def test_generate_of_own_objects_is_bounded_by_the_contour_budget(tmp_path):
    path, config = comb_too_fine_to_sample(tmp_path)
    assert_refused(*run("generate", "--out", tmp_path / "g", "--objects", path,
                        "--config", config), "comb.json", "contour_spacing_mm 0.1")
    assert not (tmp_path / "g").exists()


@pytest.mark.parametrize("command", [["ablate", "--data", "."], ["select", "--data", "."],
                                     ["study"]])
def test_every_out_folder_is_checked_before_the_work(tmp_path, command):
    blocker = tmp_path / "result"
    blocker.write_text("")
    assert_refused(*run(*command, "--out", blocker), "existing file")


# ----------------------------------------------------------------- bad data writes nothing
@pytest.fixture(scope="module")
def three_objects(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A sound dataset of 3 objects: fewer than the default 5 folds."""
    from test_dataset import toy_job

    from grip_env.config import Config
    from grip_env.dataset import generate

    config = Config().override(perception={"source": "polygon"},
                               dataset={"trials": 2, "workers": 1})
    return generate(config, tmp_path_factory.mktemp("three") / "data", objects=3,
                    progress=False, job=toy_job)


@pytest.mark.parametrize("command", ["train", "ablate", "select", "power"])
def test_a_missing_dataset_is_refused_before_out_is_created(tmp_path, command):
    out = tmp_path / "out"
    code, output = run(command, "--data", tmp_path / "nowhere", "--out", out)
    assert_refused(code, output, "nowhere")
    assert not out.exists()


@pytest.mark.parametrize("command", ["train", "ablate"])
def test_too_few_objects_for_the_folds_says_which_setting_and_writes_nothing(
        three_objects, tmp_path, command):
    out = tmp_path / "out"
    code, output = run(command, "--data", three_objects, "--out", out)
    assert_refused(code, output, "3 objects, fewer than the 5 folds of learning.folds",
                   "at most 3")
    assert not out.exists()


# ----------------------------------------------------------------- engines and cross-checks
def _relabelled(dataset: Path, folder: Path, label_model: str, engine: str | None = None) -> Path:
    """A copy of ``dataset`` whose manifest records ``label_model`` (and ``engine``)."""
    import shutil

    from grip_env.dataset.manifest import read_manifest, write_manifest

    shutil.copytree(dataset, folder)
    manifest = {**read_manifest(folder), "label_model": label_model}
    if engine is not None:
        manifest["engine"] = {"name": engine, "version": "4.0.1"}
        manifest["config"]["sim"]["engine"] = engine
    write_manifest(folder, manifest)
    return folder


@pytest.mark.parametrize("case", ["old pybullet", "old mujoco", "unknown engine"])
def test_a_crosscheck_of_labels_this_code_cannot_make_is_refused_and_writes_nothing(
        three_objects, tmp_path, case):
    pytest.importorskip("mujoco")
    label, engine, fragments = {
        "old pybullet": ("2026.12-crn", None, ("label model '2026.12-crn'", "cannot cross-check")),
        "old mujoco": ("mujoco-1999", "mujoco", ("label model 'mujoco-1999'", "in mujoco",
                                                 "cannot cross-check")),
        "unknown engine": ("2026.12-xm", "physx", ("unknown engine 'physx'",)),
    }[case]
    folder = _relabelled(three_objects, tmp_path / "data", label, engine)
    report = tmp_path / "cross.json"
    before = sorted(p.name for p in folder.rglob("*"))
    assert_refused(*run("validate", folder, "--crosscheck", 1, "--report", report), *fragments)
    assert not report.exists() and sorted(p.name for p in folder.rglob("*")) == before


def test_a_crosscheck_without_mujoco_says_how_to_install_it(three_objects, tmp_path, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "mujoco", None)  # as where it is not installed
    monkeypatch.delitem(sys.modules, "grip_env.sim.mujoco_world", raising=False)
    report = tmp_path / "cross.json"
    assert_refused(*run("validate", three_objects, "--crosscheck", 1, "--report", report),
                   "engine 'mujoco' is not installed", 'pip install "grip-env[mujoco]"')
    assert not report.exists()


def test_an_environment_without_mujoco_says_how_to_install_it(monkeypatch):
    import sys

    import gymnasium

    import grip_env.envs  # noqa: F401  (registers the environments)
    from grip_env.sim import EngineUnavailable

    monkeypatch.setitem(sys.modules, "mujoco", None)
    monkeypatch.delitem(sys.modules, "grip_env.sim.mujoco_world", raising=False)
    with pytest.raises(EngineUnavailable, match=r'pip install "grip-env\[mujoco\]"'):
        gymnasium.make("GripSelect-v0", objects=["rectangle"], engine="mujoco")


@pytest.mark.parametrize("sample", ["--resimulate", "--retest"])
@pytest.mark.parametrize("case", ["missing mujoco", "unknown engine"])
def test_a_resimulation_in_an_engine_this_code_cannot_run_is_refused_and_writes_nothing(
        three_objects, tmp_path, monkeypatch, sample, case):
    """--resimulate and --retest simulate in the dataset's own engine: without it, one line
    before any check is printed."""
    import sys

    from grip_env.label_model import MUJOCO_LABEL_MODEL

    if case == "missing mujoco":
        folder = _relabelled(three_objects, tmp_path / "data", MUJOCO_LABEL_MODEL, "mujoco")
        monkeypatch.setitem(sys.modules, "mujoco", None)  # as where it is not installed
        monkeypatch.delitem(sys.modules, "grip_env.sim.mujoco_world", raising=False)
        fragments = ("engine 'mujoco' is not installed", 'pip install "grip-env[mujoco]"')
    else:
        folder = _relabelled(three_objects, tmp_path / "data", "2026.12-xm", "physx")
        fragments = ("unknown engine 'physx'",)
    report = tmp_path / "found.json"
    assert_refused(*run("validate", folder, sample, 1, "--report", report), *fragments)
    assert not report.exists()


# ----------------------------------------------------------------- offline RL and agents (issue 47)
def test_an_export_with_more_attempts_than_candidates_writes_nothing(
        three_objects, tmp_path, monkeypatch):  # fmt: skip
    pytest.importorskip("minari")
    root = tmp_path / "minari"
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(root))
    code, output = run("export", "minari", "--data", three_objects, "--id", "grip-test/many-v0",
                       "--split", "all", "--episodes", 1, "--max-attempts", 65)  # fmt: skip
    assert_refused(code, output, "max_attempts 65 exceeds the 64 candidates")
    assert not root.exists() or not any(root.rglob("*"))


def test_a_select_config_with_more_attempts_than_candidates_writes_nothing(
        three_objects, tmp_path):  # fmt: skip
    config = tmp_path / "c.yaml"
    config.write_text("selector:\n  max_candidates: 4\n  max_attempts: 5\n")
    out = tmp_path / "out"
    code, output = run("select", "--data", three_objects, "--out", out, "--config", config)
    assert_refused(code, output, "max_attempts 5 exceeds max_candidates 4")
    assert not out.exists()
