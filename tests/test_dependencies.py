"""Every third-party module the packages import is a declared dependency of the wheel.

An import that resolves only because another dependency happens to pull its distribution in
(click through Typer until Typer vendored it) breaks the install the day that dependency changes.
The imports are read from the source's syntax tree, so a lazy import inside a function counts.
"""

from __future__ import annotations

import ast
import importlib.metadata
import re
import sys
import tomllib
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("grip_env", "classifiers")
#: Imports allowed from an optional extra only (the code imports them lazily and says which
#: extra to install when they are missing).
OPTIONAL_IMPORTS = {"ray": "cluster", "mujoco": "mujoco", "minari": "offline", "d3rlpy": "offline"}


def _normalised(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _requirement_name(requirement: str) -> str:
    return _normalised(re.match(r"[A-Za-z0-9._-]+", requirement).group())


def top_level_imports(source: str) -> Iterator[str]:
    """The top-level module of each absolute import statement in ``source``."""
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            yield from (alias.name.partition(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.module.partition(".")[0]


def third_party_imports() -> dict[str, list[str]]:
    """Each third-party top-level module imported by the packages, with the files importing it."""
    found: dict[str, list[str]] = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            for module in set(top_level_imports(path.read_text())):
                if module not in sys.stdlib_module_names and module not in PACKAGES:
                    found.setdefault(module, []).append(str(path.relative_to(ROOT)))
    return found


def test_the_audit_sees_a_lazy_import_inside_a_function():
    source = "import numpy as np\ndef f():\n    from ray.util import x\n    import os.path\n"
    assert sorted(set(top_level_imports(source))) == ["numpy", "os", "ray"]


def test_every_third_party_import_is_a_declared_dependency():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    declared = {_requirement_name(requirement) for requirement in project["dependencies"]}
    extras = {extra: {_requirement_name(requirement) for requirement in requirements}
              for extra, requirements in project["optional-dependencies"].items()}  # fmt: skip
    distributions = importlib.metadata.packages_distributions()
    undeclared = []
    for module, files in sorted(third_party_imports().items()):
        names = {_normalised(name) for name in distributions.get(module, [])}
        assert names, f"{module} (imported by {files[0]}) is installed by no distribution"
        allowed = extras[OPTIONAL_IMPORTS[module]] if module in OPTIONAL_IMPORTS else declared
        if not names & allowed:
            undeclared.append(f"{module} ({', '.join(sorted(names))}) imported by {files[0]}")
    assert not undeclared, "imported but not declared in pyproject.toml: " + "; ".join(undeclared)
