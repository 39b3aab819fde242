"""The layers of docs/architecture.md, enforced: no import against their direction.

Every ``import`` in grip_env/ and classifiers/ is read with ``ast`` (module level, inside
functions, and under ``TYPE_CHECKING`` alike) and resolved to the unit it names (a subpackage or a
top-level module of grip_env, or a subpackage of classifiers). Each unit may import only the units
its layer allows; the table below is the one docs/architecture.md explains.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FOUNDATION = {"grip_env.params", "grip_env.columns", "grip_env.config", "grip_env.shutdown",
              "grip_env.hand_geometry", "grip_env.progress", "grip_env.label_model"}
GEOMETRY = {"grip_env.objects", "grip_env.perception"}
# the planning package, and the two public paths the design's contract keeps for it
PLANNING = {"grip_env.planning", "grip_env.pipeline", "grip_env.features"}
NOT_GRIP_ENV_UPPER = {"grip_env.sim", "grip_env.dataset", "grip_env.envs", "grip_env.cli",
                      "grip_env.calibration", "grip_env.drawing", "grip_env.offline"}

# foundations: unit -> the only units of the project it may import
ONLY: dict[str, set[str]] = {
    "grip_env.params": set(),
    "grip_env.columns": set(),
    "grip_env.shutdown": set(),
    "grip_env.hand_geometry": set(),
    "grip_env.progress": set(),
    "grip_env.label_model": set(),
    "grip_env.config": {"grip_env.params", "grip_env.hand_geometry"},
    "grip_env.portable_math": set(),
    # the held worker that planning and the simulator delegate to: below both
    "grip_env.portable_process": {"grip_env.portable_math"},
}
# every other unit -> the units it must never import (foundations are always allowed)
FORBIDDEN: dict[str, set[str]] = {
    **{unit: NOT_GRIP_ENV_UPPER | PLANNING | {"classifiers"} for unit in GEOMETRY},
    # objects come from polygons, masks and images; perception (the render) builds on them
    "grip_env.objects": NOT_GRIP_ENV_UPPER | PLANNING | {"classifiers", "grip_env.perception"},
    **{unit: NOT_GRIP_ENV_UPPER | {"classifiers"} for unit in PLANNING},
    # the simulator takes the hand's kinematics from planning (finger, barrett: tested below)
    "grip_env.sim": {"grip_env.offline", "grip_env.dataset", "grip_env.envs", "grip_env.cli",
                     "grip_env.calibration", "grip_env.drawing", "grip_env.pipeline",
                     "grip_env.features", "classifiers"},
    "grip_env.mesh_sets": {"grip_env.offline", "grip_env.dataset", "grip_env.envs", "grip_env.cli",
                           "grip_env.calibration", "grip_env.drawing", "classifiers"} | PLANNING,
    "grip_env.dataset": {"grip_env.offline", "grip_env.envs", "grip_env.cli",
                         "grip_env.calibration", "grip_env.drawing", "classifiers"},
    "grip_env.calibration": {"grip_env.offline", "grip_env.envs", "grip_env.cli", "classifiers"},
    "grip_env.envs": {"grip_env.offline", "grip_env.cli", "grip_env.calibration", "classifiers"},
    "grip_env.drawing": {"grip_env.offline", "grip_env.sim", "grip_env.dataset", "grip_env.envs",
                         "grip_env.cli", "grip_env.calibration", "classifiers"},
    "grip_env.cli": set(),  # anything, classifiers only inside a command (tested below)
    # the Minari export: the environments' episodes; the CLI hands it the dataset's checksum
    "grip_env.offline": {"grip_env.cli", "classifiers"},
    "grip_env": {"classifiers", "grip_env.cli"},
    "classifiers": {"grip_env.cli"},
}
# No exception: the camera (render, then segment) is the simulator's (grip_env.sim.camera).
EXCEPTIONS: set[tuple[str, str]] = set()


@dataclass(frozen=True)
class Import:
    path: str  # file, relative to the checkout
    unit: str  # the unit the file belongs to
    target: str  # the unit it imports
    line: int
    top_level: bool  # at module level (not inside a function)


def unit_of(module: str) -> str | None:
    """``grip_env.sim.trial`` -> ``grip_env.sim``; ``classifiers.report.x`` -> ``classifiers``."""
    parts = module.split(".")
    if parts[0] == "grip_env":
        return "grip_env" if len(parts) == 1 else f"grip_env.{parts[1]}"
    if parts[0] == "classifiers":
        return "classifiers"
    return None


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _targets(node: ast.AST, module: str, is_package: bool) -> list[str]:
    if isinstance(node, ast.Import):
        return [alias.name for alias in node.names]
    if not isinstance(node, ast.ImportFrom):
        return []
    base = node.module or ""
    if node.level:
        package = module.split(".") if is_package else module.split(".")[:-1]
        package = package[: len(package) - node.level + 1]
        base = ".".join([*package, base] if base else package)
    return [f"{base}.{alias.name}" for alias in node.names] or [base]


def package_imports() -> list[Import]:
    found = []
    for root in ("grip_env", "classifiers"):
        for path in sorted((ROOT / root).rglob("*.py")):
            module = _module_name(path)
            unit = unit_of(module)
            tree = ast.parse(path.read_text(), filename=str(path))
            top = {id(node) for node in tree.body}
            top |= {id(n) for node in tree.body if isinstance(node, ast.If) for n in node.body}
            for node in ast.walk(tree):
                for name in _targets(node, module, path.name == "__init__.py"):
                    target = _resolve(name)
                    if target is not None and target != unit:
                        found.append(Import(str(path.relative_to(ROOT)), unit, target,
                                            node.lineno, id(node) in top))
    return found


def _resolve(name: str) -> str | None:
    """The unit of an imported name; ``from grip_env import datasets`` names grip_env.datasets."""
    unit = unit_of(name)
    if unit == "grip_env" and "." in name:
        candidate = name.split(".")[1]
        if (ROOT / "grip_env" / candidate).is_dir() or (ROOT / f"grip_env/{candidate}.py").exists():
            return f"grip_env.{candidate}"
    return unit


IMPORTS = package_imports()


def _forbidden(item: Import) -> bool:
    if (item.path, item.target) in EXCEPTIONS:
        return False
    if item.unit in ONLY:
        return item.target not in ONLY[item.unit]
    if item.target in FOUNDATION:
        return False
    default = FORBIDDEN["grip_env"] if item.unit.startswith("grip_env") else set()
    return item.target in FORBIDDEN.get(item.unit, default)


def test_the_scan_sees_the_package():
    units = {item.unit for item in IMPORTS}
    assert {"grip_env.sim", "grip_env.dataset", "grip_env.envs", "classifiers"} <= units
    assert any(i.unit == "grip_env.dataset" and i.target == "grip_env.sim" for i in IMPORTS)


def test_no_import_goes_against_the_layers():
    wrong = [f"{i.path}:{i.line} ({i.unit}) imports {i.target}" for i in IMPORTS if _forbidden(i)]
    assert not wrong, "imports against docs/architecture.md:\n" + "\n".join(wrong)


@pytest.mark.parametrize(("unit", "target"), [
    ("grip_env.planning", "grip_env.sim"), ("grip_env.objects", "grip_env.perception"),
    ("grip_env.sim", "grip_env.dataset"), ("grip_env.dataset", "classifiers"),
])
def test_the_named_rules_hold(unit, target):
    assert not [i for i in IMPORTS if i.unit == unit and i.target == target]


def test_grip_env_loads_classifiers_only_inside_cli_commands():
    outside = [i for i in IMPORTS if i.unit.startswith("grip_env") and i.target == "classifiers"
               and (i.unit != "grip_env.cli" or i.top_level)]
    assert not outside, [f"{i.path}:{i.line}" for i in outside]


def test_the_rules_catch_a_wrong_import():
    assert _forbidden(Import("grip_env/planning/features.py", "grip_env.planning", "grip_env.sim",
                             1, True))
    assert _forbidden(Import("grip_env/sim/x.py", "grip_env.sim", "grip_env.dataset", 1, False))
    assert _forbidden(Import("grip_env/perception/regions.py", "grip_env.perception",
                             "grip_env.sim", 1, False))
    assert not _forbidden(Import("grip_env/sim/camera.py", "grip_env.sim", "grip_env.perception",
                                 1, True))


def _imported_modules(path: str) -> set[str]:
    """Every module a file imports (``from a import b`` counts as ``a`` and ``a.b``)."""
    file = ROOT / path
    module = _module_name(file)
    tree = ast.parse(file.read_text())
    found: set[str] = set()
    for node in ast.walk(tree):
        names = _targets(node, module, file.name == "__init__.py")
        found.update(names)
        found.update(name.rsplit(".", 1)[0] for name in names if isinstance(node, ast.ImportFrom))
    return found


def test_the_report_reads_result_files_and_imports_no_experiment():
    for path in sorted((ROOT / "classifiers" / "report").glob("*.py")):
        imported = _imported_modules(str(path.relative_to(ROOT)))
        assert not [name for name in imported if name.startswith("classifiers.experiments")], \
            path.name


def test_the_study_and_its_report_do_not_import_each_other():
    study = _imported_modules("classifiers/experiments/study.py")
    report = _imported_modules("classifiers/report/study_report.py")
    assert not ("classifiers.report.study_report" in study
                and "classifiers.experiments.study" in report)


def test_the_simulator_takes_only_the_hand_s_kinematics_from_planning():
    """Never the grasps, the measures or the candidate pipeline."""
    sim = ROOT / "grip_env" / "sim"
    taken = {".".join(m.split(".")[:3]) for path in sim.glob("*.py")
             for m in _imported_modules(str(path.relative_to(ROOT)))
             if m.startswith("grip_env.planning.")}
    assert taken and taken <= {"grip_env.planning.finger", "grip_env.planning.barrett"}, taken


def test_only_the_world_touches_the_pybullet_client():
    """The hand and the trial go through ``World`` by name, as panda-gym's one PyBullet wrapper."""
    sim = Path(__file__).resolve().parents[1] / "grip_env" / "sim"
    for name in ("hand.py", "trial.py", "disturbance.py", "execution.py", "uncertainty.py"):
        text = (sim / name).read_text()
        assert ".client" not in text and "import pybullet" not in text, name


def _file_graph() -> dict[str, set[str]]:
    """File -> the project files it imports (module level, deferred and TYPE_CHECKING alike)."""
    files = {_module_name(p): str(p.relative_to(ROOT)) for root in ("grip_env", "classifiers")
             for p in (ROOT / root).rglob("*.py")}
    return {path: {files[m] for m in _direct_modules(path, files) if files[m] != path}
            for path in files.values()}


def _direct_modules(path: str, modules: dict[str, str]) -> set[str]:
    """The project modules a file names: ``from pkg import sub`` names ``pkg.sub`` when that is
    a module (its package's ``__init__`` runs first, as for any submodule, and is not counted),
    else ``pkg``."""
    file = ROOT / path
    module = _module_name(file)
    found = set()
    for node in ast.walk(ast.parse(file.read_text())):
        for name in _targets(node, module, file.name == "__init__.py"):
            if name in modules:
                found.add(name)
            elif isinstance(node, ast.ImportFrom) and name.rsplit(".", 1)[0] in modules:
                found.add(name.rsplit(".", 1)[0])
    return found


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one file (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for nxt in sorted(graph[node]):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_no_file_imports_itself_through_others():
    """No import cycle between files, deferred imports included (deferral hid the last three:
    power <-> report/power, selector evaluation <-> training, barrett <-> grasps)."""
    assert _cycles(_file_graph()) == []


def test_the_cycle_check_finds_a_cycle():
    graph = {"a.py": {"b.py"}, "b.py": {"c.py"}, "c.py": {"a.py"}, "d.py": {"a.py"}}
    assert _cycles(graph) == [["a.py", "b.py", "c.py"]]


#: classifiers/ by kind, bottom to top: estimators, the evaluation engine, the experiments that
#: write result files, and the report that reads them.
CLASSIFIER_LAYERS = ("learners", "evaluation", "experiments", "report")
#: The study is the main job: it runs the experiments, then has the report drawn.
CLASSIFIER_EXCEPTIONS = {("classifiers/experiments/study.py", "report")}


def _classifier_layer(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if parts[0] == "classifiers" and len(parts) > 2 else None


def test_classifiers_are_laid_out_by_kind_and_import_down():
    loose = [p.name for p in (ROOT / "classifiers").glob("*.py") if p.name != "__init__.py"]
    assert loose == [], "modules loose at the top of classifiers/"
    wrong = []
    for path in sorted((ROOT / "classifiers").rglob("*.py")):
        rel = str(path.relative_to(ROOT))
        layer = _classifier_layer(_module_name(path) + ".x")
        for module in _imported_modules(rel):
            target = _classifier_layer(module)
            if (layer in CLASSIFIER_LAYERS and target in CLASSIFIER_LAYERS
                    and CLASSIFIER_LAYERS.index(target) > CLASSIFIER_LAYERS.index(layer)
                    and (rel, target) not in CLASSIFIER_EXCEPTIONS):
                wrong.append(f"{rel} imports {module}")
    assert not wrong, "\n".join(wrong)
