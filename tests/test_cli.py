"""The command line as a whole: version, help that lists choices, advice that names real options."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

import grip_env
from grip_env.cli import _register_commands, app

ROOT = Path(__file__).resolve().parents[1]
_register_commands()
RUNNER = CliRunner()
COMMANDS = typer.main.get_command(app).commands


def test_version_is_the_packages():
    result = RUNNER.invoke(app, ["--version"])
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert result.exit_code == 0
    assert result.output.strip() == f"grip-env {declared}"
    assert grip_env.__version__ == declared


@pytest.mark.parametrize(("command", "choices"), [
    ("select", ["set", "flat"]),
    ("show", ["star", "rectangle", "bean"]),
    ("train", ["svm", "mlp_torch", "rank_qc", "random"]),
])
def test_help_lists_the_choices(command, choices):
    result = RUNNER.invoke(app, [command, "--help"], terminal_width=200)
    assert result.exit_code == 0
    for choice in choices:
        assert choice in result.output, (command, choice)


def test_model_names_in_help_are_the_learning_packages():
    from classifiers.learners.models import MODEL_NAMES
    from grip_env.cli.options import MODEL_NAMES_HELP

    assert MODEL_NAMES_HELP.split(", ") == list(MODEL_NAMES)
    for command in ("train", "ablate"):
        result = RUNNER.invoke(app, [command, "--help"], terminal_width=200)
        assert all(name in result.output for name in MODEL_NAMES), command


def test_a_bad_choice_is_refused_with_exit_code_2(tmp_path):
    result = RUNNER.invoke(app, ["select", "--data", ".", "--out", str(tmp_path),
                                 "--policy", "deep"])
    assert result.exit_code == 2
    assert "deep" in result.output


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_help_names_only_options_the_command_has(name):
    command = COMMANDS[name]
    own = {opt for param in command.params for opt in getattr(param, "opts", [])}
    own |= {opt for param in command.params for opt in getattr(param, "secondary_opts", [])}
    texts = [command.help or "", command.epilog or ""]
    texts += [getattr(param, "help", None) or "" for param in command.params]
    named = set(re.findall(r"(?<![\w-])--[a-z][a-z-]*", " ".join(texts)))
    assert named <= own, f"{name} --help names {sorted(named - own)}, which it lacks"


@pytest.mark.slow
def test_study_does_not_advise_an_option_it_lacks(generated_dataset_dir, tmp_path):
    out = tmp_path / "study"
    shutil.copytree(generated_dataset_dir, out / "dataset")  # made with other settings
    result = RUNNER.invoke(app, ["study", "--regenerate", "--out", str(out)])
    assert result.exit_code == 2, result.output
    message = result.output.strip().splitlines()[-1]
    assert message.startswith("error: ") and "other settings" in message
    assert "--overwrite" not in message
    assert "--out" in message


def test_registering_the_commands_loads_no_learning_code():
    script = (
        "import sys\n"
        "from grip_env.cli import _register_commands\n"
        "_register_commands()\n"
        "heavy = sorted(m for m in sys.modules if m.split('.')[0] in "
        "('classifiers', 'torch', 'sklearn', 'stable_baselines3', 'pybullet'))\n"
        "print(heavy)\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=True, cwd=ROOT)
    assert done.stdout.strip() == "[]"


def grip_env_command(*args: str) -> subprocess.CompletedProcess[str]:
    """``grip-env ARGS`` through the console-script entry point, in a fresh process."""
    return subprocess.run([sys.executable, "-c", "from grip_env.cli import main; main()", *args],
                          capture_output=True, text=True, cwd=ROOT, timeout=120)


@pytest.mark.parametrize(("args", "fragment"), [
    (["select", "--data", ".", "--out", "x", "--policy", "deep"], "'deep' is not one of"),
    (["show"], "Missing argument"),
    (["show", "star", "--grips", "many"], "--grips"),
    (["show", "square", "--sim", "--seed", "-1"], "--seed"),
    (["nosuch"], "No such command 'nosuch'"),
])
def test_usage_errors_are_one_line_with_exit_code_2(args, fragment):
    done = grip_env_command(*args)
    assert done.returncode == 2, done.stderr
    lines = [line for line in (done.stdout + done.stderr).splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and fragment in lines[0], lines
    assert "--help" in lines[0]


def test_entry_point_keeps_version_help_and_exit_codes():
    assert grip_env_command("--version").stdout.strip().startswith("grip-env ")
    help_run = grip_env_command("show", "--help")
    assert help_run.returncode == 0 and "Shape names" in help_run.stdout
    assert grip_env_command("show", "nosuch").returncode == 2


# ------------------------------------------------------------------ help, as the text reads it
def _help(*args: str) -> str:
    result = RUNNER.invoke(app, [*args, "--help"], terminal_width=200)
    assert result.exit_code == 0, result.output
    return result.output


def test_train_help_names_its_classifiers_regressors_and_rankers_from_the_registries():
    from classifiers.learners.models import MODEL_NAMES, REGRESSOR_NAMES
    from classifiers.learners.ranking import RANKER_NAMES

    text = " ".join(_help("train").split())
    for kind, names in (("Classifiers", MODEL_NAMES), ("Regressors", REGRESSOR_NAMES),
                        ("Rankers", RANKER_NAMES)):
        assert kind in text and ", ".join(names) in text, kind
    assert "{" not in text  # every placeholder filled
    assert "{" not in _help()  # and none leaks into the group's list of commands


def test_the_group_help_names_every_command():
    description = typer.main.get_command(app).help
    assert set(COMMANDS) == set(re.findall(r"[a-z]+", description.split(":", 1)[1]))
    text = _help()
    assert all(name in text.split("Options")[0] for name in COMMANDS)


def test_registering_twice_adds_no_command_twice():
    _register_commands()
    names = [info.name for info in app.registered_commands]
    assert len(names) == len(set(names)) == len(COMMANDS)


@pytest.mark.parametrize("name", ["", *sorted(COMMANDS)])
def test_flags_show_as_flags(name):
    text = _help(*[name] if name else [])
    assert "<bool>" not in text
    assert re.search(r"--help +Show this message", text), text


_ARGUMENT_COMMANDS = sorted(name for name, command in COMMANDS.items()
                            if any(isinstance(p, typer.core.TyperArgument) for p in command.params))
@pytest.mark.parametrize("name", _ARGUMENT_COMMANDS)
def test_usage_names_each_argument_as_the_help_text_does(name):
    command = COMMANDS[name]
    usage = _help(name).split("Usage:", 1)[1].splitlines()[0]
    assert "{" not in usage and "}" not in usage, usage
    words = set(re.findall(r"\b[A-Z][A-Z_]+\b", command.help or ""))
    for param in command.params:
        if isinstance(param, typer.core.TyperArgument):
            shown = param.metavar or param.name.upper()
            assert shown in [word.strip("[].") for word in usage.split()], usage
            longer = {word for word in words if word.startswith(shown) and word != shown}
            assert not longer, f"usage says {shown}, the text {sorted(longer)}"


def _int_options():
    for name, command in sorted(COMMANDS.items()):
        for param in command.params:
            if isinstance(param, typer.core.TyperOption) and \
                    param.type_descriptor.annotation is int:
                yield pytest.param(name, param.name, id=f"{name}-{param.name}")


@pytest.mark.parametrize(("name", "option"), list(_int_options()))
def test_every_seed_and_count_states_its_range(name, option):
    param = next(p for p in COMMANDS[name].params if p.name == option)
    if "seed" in option:
        assert (param.min, param.max) == (0, None), "seeds: x>=0"
    else:
        assert param.min is not None and param.min >= 0, "counts: their least (x>=1, or 0 if none)"
    lines = _help(name).split("─ Options ─", 1)[1].splitlines()  # the panel, not the text
    first = next(i for i, line in enumerate(lines) if f"--{option.replace('_', '-')} " in line)
    row = " ".join(lines[first:first + 2])  # a long type column wraps its range
    assert "x>=" in row or "<=x<=" in row, row
