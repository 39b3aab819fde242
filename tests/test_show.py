"""Drawing and ``grip-env show``: objects from every kind of spec, grips drawn where they are."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from grip_env.cli import _register_commands, app
from grip_env.drawing import add_grip_legend, grip_legend, label_extent, object_figure
from grip_env.objects import make_shape, object_from_spec
from grip_env.objects.shapes import rectangle
from grip_env.perception.regions import find_regions
from grip_env.planning.pipeline import candidates
from grip_env.sim import TrialResult
from grip_env.sim.trial import grams


@pytest.fixture(scope="module")
def runner() -> CliRunner:
    _register_commands()
    return CliRunner()


def test_show_draws_regions_and_best_grips(runner, tmp_path):
    out = tmp_path / "star.png"
    result = runner.invoke(app, ["show", "star", "--grips", "3", "--out", str(out)])
    assert result.exit_code == 0, result.output
    with Image.open(out) as image:
        assert image.size[0] >= 500 and image.size[1] >= 500


def test_show_says_when_an_object_has_grips_only_with_frictional_closure(runner, tmp_path):
    result = runner.invoke(app, ["show", "cross", "--grips", "3", "--out", str(tmp_path / "a.png")])
    assert result.exit_code == 2, result.output
    assert "has no feasible grip" in result.output
    assert "need normals that span the plane without friction" in result.output
    assert "synthesis.frictional_closure: true) it has" in result.output
    assert not (tmp_path / "a.png").exists()
    config = tmp_path / "friction.yaml"
    config.write_text("synthesis:\n  frictional_closure: true\n")
    result = runner.invoke(app, ["show", "cross", "--grips", "3", "--config", str(config),
                                 "--out", str(tmp_path / "b.png")])
    assert result.exit_code == 0, result.output
    assert "no grip" not in result.output


@pytest.mark.slow
def test_show_sim_writes_a_strip_of_the_trial(runner, tmp_path):
    out = tmp_path / "trial.png"
    result = runner.invoke(app, ["show", "rectangle", "--sim", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "held" in result.output or "slipped" in result.output
    with Image.open(out) as image:
        assert image.size[0] > 3 * image.size[1]  # frames side by side


@pytest.mark.parametrize(("args", "said"), [
    (["nosuch"], "error:"), (["star", "--grips", "-1"], "greater than or equal to 0")])
def test_show_refuses_bad_input_with_exit_code_2(runner, tmp_path, args, said):
    result = runner.invoke(app, ["show", *args, "--out", str(tmp_path / "x.png")])
    assert result.exit_code == 2
    assert said in result.output
    assert not (tmp_path / "x.png").exists()


def test_objects_from_vertex_and_image_files(tmp_path):
    vertices = rectangle(80, 40)
    (tmp_path / "box.json").write_text(json.dumps(vertices.tolist()))
    np.savetxt(tmp_path / "box.csv", vertices, delimiter=",")
    mask = np.zeros((60, 100), dtype=np.uint8)
    mask[10:50, 10:90] = 255
    Image.fromarray(mask).save(tmp_path / "box.png")
    for name in ("box.json", "box.csv"):
        assert object_from_spec(str(tmp_path / name)).area == pytest.approx(3200)
    assert object_from_spec(str(tmp_path / "box.png"), mm_per_px=1.0).area == pytest.approx(
        3200, rel=0.03
    )
    (tmp_path / "box.txt").write_text("1,2")
    with pytest.raises(ValueError, match="unknown type"):
        object_from_spec(str(tmp_path / "box.txt"))


def test_finger_lines_start_at_the_spread_axes_and_the_palm():
    obj = make_shape("triangle")
    grip = candidates(obj).iloc[0]
    fig = object_figure(obj, grips=candidates(obj).head(1))
    dashed = [line.get_xydata() for line in fig.axes[0].lines if line.get_linestyle() == "--"]
    starts = np.array([line[0] for line in dashed])
    yaw = grip["hand_yaw"]
    x_axis = np.array([np.sin(yaw), -np.cos(yaw)])  # hand x = thumb force turned clockwise
    palm = np.array([grip["hand_x"], grip["hand_y"]])
    np.testing.assert_allclose(starts, [palm + 25 * x_axis, palm - 25 * x_axis, palm], atol=1e-9)


# ------------------------------------------------------------------ issue 35, items 7 to 9
def _result(**fields) -> TrialResult:
    base = {"success": False, "robustness_g": 0.0, "held": False, "drift_mm": 0.0,
            "rotation_deg": 0.0, "lifted_mm": 60.0, "steps": 500, "close_steps": 26,
            "reference_g": 64.0, "failed_at": "ramp"}
    return TrialResult(**{**base, **fields})


@pytest.mark.parametrize(("fields", "words"), [
    ({"success": True, "held": True, "robustness_g": 90.50966799187808, "failed_at": ""},
     "held up to 90.5 g against the reference of 64 g"),
    ({"held": True, "robustness_g": 53.8173705762377},
     "held after the lift, then slipped at the ramp: held up to 53.8 g, short of the reference "
     "of 64 g"),
    ({"held": True, "robustness_g": 0.0},
     "held after the lift, then slipped at the ramp's first level (the reference of 64 g)"),
    ({"lifted_mm": 1.24, "drift_mm": 40.0, "failed_at": "lift"},
     "dropped at the lift (the object rose only 1.2 mm)"),
    ({"drift_mm": 7.26, "rotation_deg": 2.0, "failed_at": "hold"},
     "slipped in the hand at the lift (drift 7.3 mm, turn 2.0 deg after the hold)"),
])
def test_a_trial_outcome_reads_as_what_happened(fields, words):
    # was "slipped (drift 0.0 mm)" for a trial that held after the lift and failed the ramp
    assert _result(**fields).describe() == words


@pytest.mark.slow
@pytest.mark.parametrize(("args", "rows"), [([], 1), (["--grips", "2"], 2)])
def test_show_sim_draws_the_phases_and_outcome_of_each_asked_grip(
    runner, tmp_path, monkeypatch, args, rows
):
    import grip_env.drawing
    import grip_env.sim

    drawn, simulated = [], []
    real_figure, real_frames = grip_env.drawing.trial_figure, grip_env.sim.trial_frames
    monkeypatch.setattr(grip_env.drawing, "trial_figure",
                        lambda r, title=None: drawn.append(r) or real_figure(r, title))
    monkeypatch.setattr(grip_env.sim, "trial_frames",
                        lambda *a, **k: simulated.extend(real_frames(*a, **k)) or simulated)
    out = tmp_path / "trial.png"
    result = runner.invoke(app, ["show", "rectangle", "--sim", *args, "--out", str(out)])
    assert result.exit_code == 0, result.output
    [figure_rows] = drawn
    assert len(figure_rows) == len(simulated) == rows  # --grips was ignored with --sim
    from grip_env.dataset import planned_candidates

    best = planned_candidates(make_shape("rectangle"))[1].head(rows)  # as generate plans it
    lines = [line for line in result.output.splitlines() if line.startswith("trial of")]
    for (title, frames), (trial, _), grip_id, line in zip(
        figure_rows, simulated, best["grip_id"], lines, strict=True
    ):
        # the words are the real trial's: its robustness against its reference, or its phase
        assert line == f"trial of {grip_id} in pybullet: {trial.describe()}"
        assert title.endswith(trial.describe())
        if trial.held:
            assert f"up to {grams(trial.robustness_g)}" in line
            assert f"reference of {grams(trial.reference_g)}" in line
        assert [phase.split("\n")[0] for phase, _ in frames] == [
            "1 approach", "2 close", "3 lift and hold", "4 disturbance ramp"]
        approach = frames[0][1]
        blue = (approach[..., 2].astype(int) - approach[..., :2].max(axis=2)) > 60
        assert blue.sum() > 200  # the object, painted apart from the black and red hand
    with Image.open(out) as image:
        assert image.size[1] > rows * 250


@pytest.mark.slow
def test_pictures_of_a_trial_leave_its_outcome_as_the_labels_have_it():
    from grip_env.config import Config
    from grip_env.sim import run_trial_outcomes, trial_frames

    obj = make_shape("rectangle")
    grip = candidates(obj).head(1)
    [(result, frames)] = trial_frames(obj, grip, Config(), seed=3, width=64, height=48)
    [label] = run_trial_outcomes(obj, grip, Config(), trials=1, seed=3).itertuples()
    assert (result.robustness_g, result.success, result.held, result.steps) == (
        label.robustness, label.success, label.held, label.steps)
    assert list(frames) == (["approach", "closed", "held", "ramp"] if result.held
                            else ["approach", "closed", "held"])


def test_grip_labels_do_not_overlap():
    obj = make_shape("star")
    regions = find_regions(obj)
    grips = candidates(obj, regions=regions).head(3)
    fig = object_figure(obj, regions, grips)
    labels = [t for t in fig.axes[0].texts if t.get_text().startswith("#")]
    assert len(labels) == 3
    palms = fig.axes[0].transData.transform(grips[["hand_x", "hand_y"]].to_numpy())
    height = label_extent(labels[0]).height
    # the case of the issue: two palms closer than a label's height
    assert min(np.linalg.norm(palms[i] - palms[j]) for i in range(3) for j in range(i)) < height
    boxes = [label_extent(label) for label in labels]
    for i, box in enumerate(boxes):
        for other in boxes[:i]:
            assert not box.padded(1.0).overlaps(other), (box, other)


def test_a_legend_explains_the_marks_and_the_study_gallery_uses_the_same():
    from classifiers.report import figures

    obj = make_shape("star")
    fig = object_figure(obj, find_regions(obj), candidates(obj).head(3))
    [legend] = fig.legends
    names = " | ".join(text.get_text() for text in legend.get_texts())
    for mark in ("contacts of fingers", "finger forces", "finger lines", "contact triangle",
                 "palm centre", "grasp focus C_G", "real focus C_C", "grasping region",
                 "centroid", "best grip", "faint"):
        assert mark in names
    assert figures.grip_legend is grip_legend and figures.add_grip_legend is add_grip_legend


@pytest.mark.parametrize(("spec", "kind"), [("nosuchfile.png", "image file"),
                                            ("parts/nosuch.json", "vertex file"),
                                            ("nosuch.obj", "mesh file"),
                                            ("parts/nosuch", "file")])
def test_show_says_a_missing_file_does_not_exist(runner, tmp_path, monkeypatch, spec, kind):
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["show", spec, "--out", str(tmp_path / "x.png")])
    assert result.exit_code == 2
    assert f"error: {kind} {spec} does not exist (looked for {tmp_path / spec})" in result.output
    assert "known shape" not in result.output


@pytest.mark.parametrize("command", ["generate", "show"])
def test_a_missing_object_file_is_missing_for_generate_and_show_alike(runner, tmp_path,
                                                                       monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / ("data" if command == "generate" else "x.png")
    flag = ["--objects", "nosuch.png"] if command == "generate" else ["nosuch.png"]
    result = runner.invoke(app, [command, *flag, "--out", str(out)])
    assert result.exit_code == 2
    assert "error: image file nosuch.png does not exist" in result.output
    assert not out.exists()
