"""The source a study stage runs, as a digest: every project module its run function reaches by
import, read as text, so that a rerun recomputes a stage whose code changed at the same grip-env
version (a checkout between releases) and reuses one whose code did not.

The modules are found by reading imports, not by importing: every ``import`` anywhere in a
module (inside functions too) counts, so the set errs on the side of more modules, and a stage
is recomputed rather than reused when in doubt.
"""

from __future__ import annotations

import ast
import hashlib
import inspect
from collections.abc import Callable, Iterable
from functools import cache
from pathlib import Path

#: The top-level packages whose source a stage's digest covers.
PROJECT_PACKAGES = ("grip_env", "classifiers")
#: The folder holding them.
SOURCE_ROOT = Path(__file__).resolve().parents[2]


def stage_code_digest(run: Callable[..., object]) -> str:
    """SHA-256 of ``run``'s source, of the functions of its own module it calls, and of every
    project module these (or the module's top-level imports) reach by import."""
    module = inspect.getmodule(run)
    assert module is not None
    tree = ast.parse(inspect.getsource(module))
    functions = _called_functions(tree, run.__name__)
    top_level = [node for node in tree.body if isinstance(node, ast.Import | ast.ImportFrom)]
    start = _imported(ast.Module(body=[*functions, *top_level], type_ignores=[]),
                      run.__module__, is_package=False)
    digest = hashlib.sha256()
    for function in functions:
        digest.update(ast.dump(function).encode())
    for name in sorted(reachable_modules(start)):
        digest.update(name.encode() + b"\0" + _source(name) + b"\0")
    return digest.hexdigest()


def _called_functions(tree: ast.Module, name: str) -> list[ast.FunctionDef]:
    """The module-level function ``name`` and those of its module it names, transitively."""
    defined = {node.name: node for node in tree.body if isinstance(node, ast.FunctionDef)}
    found: dict[str, ast.FunctionDef] = {}
    waiting = [name]
    while waiting:
        current = waiting.pop()
        if current in found or current not in defined:
            continue
        found[current] = defined[current]
        waiting.extend(node.id for node in ast.walk(defined[current])
                       if isinstance(node, ast.Name) and node.id in defined)
    return [found[key] for key in sorted(found)]


def reachable_modules(start: Iterable[str]) -> set[str]:
    """The project modules in ``start`` and every project module they import, transitively."""
    found: set[str] = set()
    waiting = [m for m in start if _path(m) is not None]
    while waiting:
        module = waiting.pop()
        if module in found:
            continue
        found.add(module)
        waiting.extend(m for m in _imports_of(module) if m not in found)
    return found


@cache
def _imports_of(module: str) -> tuple[str, ...]:
    path = _path(module)
    assert path is not None
    tree = ast.parse(path.read_bytes(), filename=str(path))
    return tuple(_imported(tree, module, is_package=path.name == "__init__.py"))


def _imported(tree: ast.AST, module: str, is_package: bool) -> list[str]:
    """The project modules (and their parent packages) that the imports in ``tree`` name."""
    package = module if is_package else module.rpartition(".")[0]
    names: list[str] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.extend(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = _absolute(node, package)
            names.append(base)
            names.extend(f"{base}.{alias.name}" for alias in node.names)  # submodules, if any
    return [m for name in names for m in _with_parents(name) if _path(m) is not None]


def _absolute(node: ast.ImportFrom, package: str) -> str:
    if not node.level:
        return node.module or ""
    parts = package.split(".")
    base = ".".join(parts[: len(parts) - node.level + 1])
    return f"{base}.{node.module}" if node.module else base


def _with_parents(name: str) -> list[str]:
    parts = name.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts) + 1)]


@cache
def _path(module: str) -> Path | None:
    """The source file of a project module or package, or None for anything else."""
    if module.split(".")[0] not in PROJECT_PACKAGES:
        return None
    stem = SOURCE_ROOT.joinpath(*module.split("."))
    for path in (stem.with_suffix(".py"), stem / "__init__.py"):
        if path.is_file():
            return path
    return None


def _source(module: str) -> bytes:
    path = _path(module)
    assert path is not None
    return path.read_bytes()
