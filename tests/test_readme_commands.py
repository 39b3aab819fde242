"""The README's commands, walked in order on a fresh small dataset, so the README cannot drift
from the code: every line of its "Commands" block (and its small-dataset benchmark line) runs
here, made small only by the adaptations listed beside it."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from grip_env.cli import _register_commands, app

ROOT = Path(__file__).resolve().parents[1]
#: Settings that shrink every command's work (each command also reads them with --config).
TINY = """\
objects: {mesh_count: 0}
dataset: {max_grips_per_object: 6, workers: 1}
learning: {folds: 2, repeats: 1, seeds: 1}
selector: {timesteps: 128, seeds: 1, n_envs: 2, rollout_steps: 64, batch_size: 32,
           max_candidates: 8}
"""
#: How each README command is made small: (README text, replaced by) pairs, or None to run it as
#: written; a command whose small form is another test's is named with that test.
SMALL: dict[str, list[tuple[str, str]] | str | None] = {
    "show star --grips 3 --out star.png": None,
    "show rectangle --sim --out trial.png": None,
    "show part.png --mm-per-px 0.5 --out p.png": None,
    "show duck --grips 3 --out duck.png": None,
    "generate --out data --objects default --trials 4 --workers 2":
        [("--objects default", "--objects 10"), ("--trials 4", "--trials 2"),
         ("--workers 2", "--workers 1")],
    "generate --out data200 --objects 200 --seed 1": [("--objects 200", "--objects 2")],
    "generate --out mine --objects parts/ --mm-per-px 0.5": None,
    "validate data": None,
    "validate data --resimulate 20 --retest 4": [("--resimulate 20", "--resimulate 4"),
                                                ("--retest 4", "--retest 1")],
    "train --data data --out models": None,
    "predict --model models/models/svm.json --data mine": None,
    "ablate --data data --out ablation": None,
    "select --data data --out selector": None,
    "benchmark agent.zip --data data --out lb": [("agent.zip", "selector/model.zip")],
    "calibrate --out calib": [("calibrate", "calibrate --quick")],
    "power --data data --out power": None,
    "study --out runs/default": "tests/test_study.py (the whole study, on --quick)",
    "study --quick --out runs/quick": "tests/test_study.py",
    "study --out runs/default --update-readme": "tests/test_study.py (--update-readme)",
    "--version": None,
    "benchmark mysel:pick --data data --out lb": [("--out lb", "--out lb_pick")],
}
#: Commands that cannot run on data this small and must say so in one line (exit code 2).
REFUSED_WHEN_SMALL = {
    "power --data data --out power": "use a dataset of more objects",
}
#: Commands that read no config file.
NO_CONFIG = ("validate", "predict", "--version")


def readme_commands() -> list[str]:
    """The ``grip-env`` lines of the README's Commands block, then its small-dataset benchmark
    line, without the comments."""
    text = (ROOT / "README.md").read_text()
    block = text.split("## Commands", 1)[1].split("```bash", 1)[1].split("```", 1)[0]
    lines = [line.split("#", 1)[0].strip() for line in block.splitlines()]
    found = [line.removeprefix("grip-env ") for line in lines if line.startswith("grip-env")]
    found += re.findall(r"^grip-env (benchmark mysel:pick [^#\n]*?)\s+#", text, flags=re.M)
    return found


def small_form(command: str) -> list[str]:
    """The README command made small by its :data:`SMALL` entry, with the tiny config."""
    line = command
    for old, new in SMALL[command] or []:  # type: ignore[union-attr]
        assert old in line, f"{command!r} no longer says {old!r}"
        line = line.replace(old, new)
    args = shlex.split(line)
    return args if args[0] in NO_CONFIG else [*args, "--config", "tiny.yaml"]


def test_every_readme_command_has_its_small_form():
    assert readme_commands() == list(SMALL)


def _own_files(folder: Path) -> None:
    """``part.png`` and ``parts/`` (one image each): an object on a contrasting background."""
    image = np.zeros((200, 260), np.uint8)
    image[40:160, 50:220] = 255
    image[40:90, 50:110] = 0  # a notch: an L-shaped part
    Image.fromarray(image).save(folder / "part.png")
    (folder / "parts").mkdir()
    Image.fromarray(image).save(folder / "parts" / "bracket.png")
    (folder / "mysel.py").write_text("def pick(candidates):\n    return -candidates['Q_C']\n")


@pytest.mark.slow
def test_the_readme_commands_run_in_order_on_a_small_dataset(tmp_path, monkeypatch):
    _register_commands()
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tiny.yaml").write_text(TINY)
    _own_files(tmp_path)
    runner = CliRunner()
    for command in readme_commands():
        if isinstance(SMALL[command], str):
            continue  # walked by the test SMALL names
        args = small_form(command)
        result = runner.invoke(app, args)
        if command in REFUSED_WHEN_SMALL:
            assert result.exit_code == 2, result.output
            assert REFUSED_WHEN_SMALL[command] in result.output
            continue
        assert result.exit_code == 0, f"grip-env {' '.join(args)}\n{result.output}"
    for written in ("star.png", "trial.png", "p.png", "duck.png", "data/manifest.json",
                    "mine/manifest.json", "models/metrics.json", "predictions.parquet",
                    "ablation/ablation.json", "selector/model.zip", "lb/leaderboard.md",
                    "calib/calibration.md", "lb_pick/leaderboard.json"):
        assert (tmp_path / written).exists(), written
