"""The documented commands, walked in order on a fresh small dataset, so the documentation cannot
drift from the code: every line of the commands page's block (``docs/reference/commands.md``) runs
here, made small only by the adaptations listed beside it; the README keeps the two commands that
set everything up."""

from __future__ import annotations

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
#: How each documented command is made small: (README text, replaced by) pairs, or None to run it as
#: written; a command whose small form is another test's is named with that test.
SMALL: dict[str, list[tuple[str, str]] | str | None] = {
    "show star --grips 3 --out star.png": None,
    "show rectangle --sim --out trial.png": None,
    "show part.png --mm-per-px 0.5 --out p.png": None,
    "candidates part.png --mm-per-px 0.5 --top 5": None,
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
    "benchmark mysel:pick --data data --out lb": [("--out lb", "--out lb_pick")],
    "calibrate --out calib": [("calibrate", "calibrate --quick")],
    "power --data data --out power": None,
    "study --out runs/default": "tests/test_study.py (the whole study, on --quick)",
    "study --quick --out runs/quick": "tests/test_study.py",
    "study --out runs/default --update-readme": "tests/test_study.py (--update-readme)",
    "--version": None,
}
#: Commands that cannot run on data this small and must say so in one line (exit code 2).
REFUSED_WHEN_SMALL = {
    "power --data data --out power": "use a dataset of more objects",
}
#: Commands that read no config file.
NO_CONFIG = ("validate", "predict", "--version")


COMMANDS_PAGE = ROOT / "docs" / "reference" / "commands.md"
#: The README's two commands: they set up everything themselves (``.ci/run`` runs the second).
TWO_COMMANDS = ("bash scripts/study.sh", "bash scripts/test.sh")


def readme_commands() -> list[str]:
    """The ``grip-env`` lines of the commands page's first ``bash`` block, without comments."""
    block = COMMANDS_PAGE.read_text().split("```bash", 1)[1].split("```", 1)[0]
    lines = [line.split("#", 1)[0].strip() for line in block.splitlines()]
    return [line.removeprefix("grip-env ") for line in lines if line.startswith("grip-env")]


def test_the_readme_keeps_the_two_commands():
    readme = (ROOT / "README.md").read_text()
    block = readme.split("## The two commands", 1)[1].split("```bash", 1)[1].split("```", 1)[0]
    commands = [line.split("#", 1)[0].strip() for line in block.splitlines() if line.strip()]
    assert commands == list(TWO_COMMANDS)
    assert all(Path(ROOT, command.split()[1]).is_file() for command in TWO_COMMANDS)


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
