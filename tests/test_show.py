"""Drawing and ``grip-env show``: objects from every kind of spec, grips drawn where they are."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from grip_env.cli import _register_commands, app
from grip_env.drawing import object_figure
from grip_env.objects import make_shape, object_from_spec
from grip_env.objects.shapes import rectangle
from grip_env.planning.pipeline import candidates


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


@pytest.mark.slow
def test_show_sim_writes_a_strip_of_the_trial(runner, tmp_path):
    out = tmp_path / "trial.png"
    result = runner.invoke(app, ["show", "rectangle", "--sim", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "held" in result.output or "slipped" in result.output
    with Image.open(out) as image:
        assert image.size[0] > 3 * image.size[1]  # frames side by side


@pytest.mark.parametrize("args", [["nosuch"], ["star", "--grips", "-1"]])
def test_show_refuses_bad_input_with_exit_code_2(runner, tmp_path, args):
    result = runner.invoke(app, ["show", *args, "--out", str(tmp_path / "x.png")])
    assert result.exit_code == 2
    assert "error:" in result.output


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
