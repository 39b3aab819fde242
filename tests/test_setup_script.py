"""``source scripts/setup.sh`` (test.sh, study.sh and docs.sh do it) leaves the caller's shell as
it was: its options and working directory, so that an interactive shell survives a later failing
command. The real script runs on a copy of the checkout whose install stamp is current, so it
installs nothing."""

from __future__ import annotations

import hashlib
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHELL_OPTIONS = ("errexit", "nounset", "pipefail")


@pytest.fixture
def checkout(tmp_path: Path) -> Path:
    """A checkout holding setup.sh and pyproject.toml, with a .venv already up to date."""
    (tmp_path / "scripts").mkdir()
    shutil.copy2(ROOT / "scripts" / "setup.sh", tmp_path / "scripts" / "setup.sh")
    shutil.copy2(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    python = tmp_path / ".venv" / "bin" / "python"
    python.parent.mkdir(parents=True)
    python.write_text("#!/bin/sh\nexit 1\n")  # any call to it would fail the script
    python.chmod(0o755)
    stamp = hashlib.sha256((tmp_path / "pyproject.toml").read_bytes()
                           + (tmp_path / "scripts" / "setup.sh").read_bytes()).hexdigest()
    (tmp_path / ".venv" / ".grip-env-installed").write_text(stamp + "\n")
    return tmp_path


def _options_after_sourcing(checkout: Path, before: str) -> tuple[dict[str, str], str]:
    setup = checkout / "scripts" / "setup.sh"
    script = f"{before}\nsource {setup} || exit 3\necho \"cwd=$PWD\"\nset -o\n"
    done = subprocess.run(["bash", "--norc", "--noprofile", "-c", script], cwd=checkout / "scripts",
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and not done.stderr, done.stdout + done.stderr
    lines = done.stdout.splitlines()
    options = dict(line.split() for line in lines[1:] if len(line.split()) == 2)
    return {name: options[name] for name in SHELL_OPTIONS}, lines[0].removeprefix("cwd=")


def test_sourcing_setup_leaves_the_callers_options_and_folder_as_they_were(checkout):
    options, cwd = _options_after_sourcing(checkout, "set +euo pipefail")
    assert options == dict.fromkeys(SHELL_OPTIONS, "off")
    assert Path(cwd) == checkout / "scripts"
    options, _ = _options_after_sourcing(checkout, "set -euo pipefail")
    assert options == dict.fromkeys(SHELL_OPTIONS, "on")


def test_a_failing_setup_is_a_failed_source_not_a_closed_shell(checkout):
    (checkout / "pyproject.toml").unlink()  # the stamp cannot be computed: the setup fails
    script = "source scripts/setup.sh; echo status=$?; echo still here"
    done = subprocess.run(["bash", "--norc", "--noprofile", "-c", script], cwd=checkout,
                          capture_output=True, text=True, timeout=60)
    assert done.stdout.split() == ["status=1", "still", "here"], done.stdout + done.stderr
