"""A normal (non-editable) install works: build the wheel, install it into a fresh venv, run it.

The fresh venv holds only what the wheel's own metadata asks for: CPU torch first (any other
torch build pulls CUDA; that wheel lies in pip's find-links on the CI machines), then the wheel
with its dependencies resolved by pip from the package index. Nothing is borrowed from the
development environment, so an import that only a dev or extra package satisfies fails here.
Everything runs from a folder outside the checkout, so only the wheel's files can be found.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SOURCES = ("pyproject.toml", "README.md", "LICENSE", "grip_env", "classifiers")
_IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc", "*.egg-info")


def build_wheel(work: Path) -> Path:
    """The wheel of a copy of the checkout (so the build leaves nothing in the working tree)."""
    source = work / "src"
    source.mkdir()
    for name in SOURCES:
        origin = ROOT / name
        if origin.is_dir():
            shutil.copytree(origin, source / name, ignore=_IGNORE)
        else:
            shutil.copy2(origin, source / name)
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--no-build-isolation",
         "--no-index", "--wheel-dir", str(work / "dist"), str(source)],
        check=True, capture_output=True, text=True,
    )
    (wheel,) = (work / "dist").glob("grip_env-*.whl")
    return wheel


#: Installed before the wheel, so that the wheel's ``torch`` requirement is met by the CPU build.
TORCH = "torch==2.13.0"


def fresh_venv(work: Path, wheel: Path) -> Path:
    """A new venv holding CPU torch, the wheel and the wheel's dependencies, and nothing else."""
    venv = work / "venv"
    base = getattr(sys, "_base_executable", sys.executable)
    subprocess.run([base, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    for requirement in (TORCH, str(wheel)):
        done = subprocess.run(
            [sys.executable, "-m", "pip", "--python", str(python), "install", "--quiet",
             requirement], capture_output=True, text=True, timeout=1800,
        )
        assert done.returncode == 0, done.stdout + done.stderr
    return venv


def run_outside(venv: Path, cwd: Path, *command: str) -> str:
    env = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    done = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def test_citation_license_and_readme_agree_with_the_project():
    import tomllib

    import yaml

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    citation = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert citation["version"] == project["version"]
    assert citation["license"] == project["license"] == "MIT"
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")
    paper = citation["references"][0]
    readme = (ROOT / "README.md").read_text()
    opening = readme[: readme.index("## The two commands")]
    assert f"title   = {{{paper['title']}}}" in opening  # the BibTeX entry
    assert str(paper["year"]) in opening and paper["journal"] in opening
    for author in paper["authors"]:
        assert author["family-names"] in opening


@pytest.mark.slow
def test_wheel_installs_and_runs_outside_the_checkout(tmp_path):
    wheel = build_wheel(tmp_path)
    names = zipfile.ZipFile(wheel).namelist()
    assert "grip_env/assets/barrett_bh8_280.urdf" in names
    assert any(name.endswith("licenses/LICENSE") for name in names)
    venv = fresh_venv(tmp_path, wheel)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    absent = "import importlib.util as u; print(u.find_spec('pytest'), u.find_spec('ray'))"
    out = run_outside(venv, elsewhere, str(venv / "bin" / "python"), "-c", absent)
    assert out.split() == ["None", "None"]  # neither a dev nor an extra package: truly fresh
    version = run_outside(venv, elsewhere, str(venv / "bin" / "grip-env"), "--version")
    assert "grip-env 0.1.0" in version, version
    out = run_outside(venv, elsewhere, str(venv / "bin" / "grip-env"), "show", "star",
                      "--out", "star.png")
    assert out.strip() == "wrote star.png"
    assert (elsewhere / "star.png").read_bytes()[:4] == b"\x89PNG"
    script = (
        "import gymnasium, grip_env, pathlib, sys\n"
        "assert pathlib.Path(grip_env.__file__).is_relative_to(sys.prefix), grip_env.__file__\n"
        "env = gymnasium.make('GripSelect-v0')\n"
        "obs, info = env.reset(seed=0)\n"
        "obs, reward, done, cut, info = env.step(int(obs['mask'].argmax()))\n"
        "print(info['object_id'], 'is_success' in info)\n"
    )
    out = run_outside(venv, elsewhere, str(venv / "bin" / "python"), "-c", script)
    assert out.split()[-1] == "True"


if __name__ == "__main__":  # the CI's wheel check: python tests/test_packaging.py
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        test_wheel_installs_and_runs_outside_the_checkout(Path(folder))
    print("wheel check: grip-env --version, grip-env show star and gymnasium.make('GripSelect-v0')"
          " ran from a wheel in a venv holding only its dependencies")
