"""What a method was trained on, and whether it saw a held-out object of the split.

A score on objects the method learnt from is in-sample: the benchmark refuses it. Each kind of
method carries its record of training objects (:data:`RECORD_KEY`, a list of object ids):

- a model ``grip-env train`` saved: its ``NAME.json`` (``trained_on``; a file saved before
  these records holds only ``dataset_sha256``: equal to the benchmarked dataset's, it was fitted
  on every object of it);
- an SB3 zip: ``NAME.json`` beside ``NAME.zip`` (``grip-env select`` writes it;
  :func:`write_agent_record` writes it for your own agent); an RL Zoo run: the env's split
  recorded in its ``GripSelect-v0/args.yml`` (``--env-kwargs``), whose objects are re-derived;
- a function or class: an attribute ``trained_on`` (object ids; empty when it learns nothing).

- a d3rlpy policy (``NAME.d3``): ``NAME.json`` beside it, which
  :func:`classifiers.experiments.offline_rl.train_offline` writes from the Minari export's own
  record of its objects.

A method without a record is scored and marked: its leaderboard row and line say that the
benchmark could not check what it learnt from.

The training budget (:func:`recorded_budget`, :func:`function_budget`) is read the same way:
an SB3 zip's environment steps (``num_timesteps``), the ``budget`` entry of ``NAME.json`` (a
d3rlpy policy: the export's transitions and episodes), a function's ``training_budget``.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

RECORD_KEY = "trained_on"
#: RL Zoo keeps a run's arguments in ``<run>/<env id>/args.yml`` beside ``<run>/<env id>.zip``.
RL_ZOO_ARGS = "args.yml"


@dataclass(frozen=True)
class Recorded:
    """One method file's record: the object ids it trained on (None: not recorded), where the
    record came from, and why there is none."""

    objects: tuple[str, ...] | None
    source: str
    missing: str = ""


def training_record(objects: Iterable[str], dataset_sha256: str | None = None,
                    **split: Any) -> dict[str, Any]:  # fmt: skip
    """The ``trained_on`` entry of a model's or agent's metadata: sorted object ids, the
    dataset's checksum and the split that chose them (name, version, seed...)."""
    record: dict[str, Any] = {"objects": sorted({str(o) for o in objects}), **split}
    if dataset_sha256 is not None:
        record["dataset_sha256"] = dataset_sha256
    return record


def write_agent_record(zip_path: str | Path, env: Any, **split: Any) -> Path:
    """Write ``NAME.json`` beside an SB3 agent's ``NAME.zip``: the objects of ``env`` (a
    ``GripSelect-v0``/``GripAccept-v0`` env, wrapped or vectorised) it was trained on; ``split``
    entries are added to the record (``split`` itself replaces the env's split name)."""
    path = Path(zip_path).with_suffix(".json")
    split = {"split": _env_split(env), **split}
    record = training_record(env_objects(env), **split)
    path.write_text(json.dumps({RECORD_KEY: record}, indent=2))
    return path


def env_objects(env: Any) -> tuple[str, ...]:
    """The object ids a grip environment draws its episodes from."""
    if hasattr(env, "get_attr"):  # a VecEnv: its first env's objects (all share one split)
        return tuple(env.get_attr("object_ids", indices=[0])[0])
    return tuple(env.unwrapped.object_ids)


def _env_split(env: Any) -> str:
    if hasattr(env, "get_attr"):
        return str(env.get_attr("split", indices=[0])[0])
    return str(env.unwrapped.split)


# ------------------------------------------------------------------ reading the records
def recorded_file(path: Path, dataset_sha256: str, dataset_objects: Sequence[str]) -> Recorded:
    """The record of a saved model (``.json``/``.skops``/``.pt``/``.txt``) or SB3 zip."""
    meta = path.with_suffix(".json")
    info = _json(meta) if meta.is_file() else None
    if isinstance(info, dict) and isinstance(info.get(RECORD_KEY), dict):
        objects = info[RECORD_KEY].get("objects")
        if isinstance(objects, list):
            return Recorded(tuple(map(str, objects)), meta.name)
    if isinstance(info, dict) and info.get("dataset_sha256") == dataset_sha256:
        return Recorded(tuple(dataset_objects), f"{meta.name} (dataset_sha256 is this dataset's: "
                                                f"fitted on all of it)")  # fmt: skip
    if path.suffix.lower() == ".zip":
        return rl_zoo_record(path)
    where = meta.name if meta.is_file() else f"no {meta.name} beside it"
    return Recorded(None, "", f"{path.name}: no record of its training objects ({where})")


def rl_zoo_record(path: Path) -> Recorded:
    """The objects an RL Zoo agent trained on, from its run's ``args.yml`` (``env_kwargs``:
    the dataset and split), re-derived by making the same environment."""
    args_file = path.parent / path.stem / RL_ZOO_ARGS
    none = Recorded(None, "", f"{path.name}: no record of its training objects (no {path.stem}"
                              f".json beside it, nor an RL Zoo {args_file.parent.name}/"
                              f"{RL_ZOO_ARGS})")  # fmt: skip
    if not args_file.is_file():
        return none
    try:
        args = yaml.load(args_file.read_text(), Loader=_ZooLoader)
    except (yaml.YAMLError, ValueError) as exc:
        return Recorded(None, "", f"{path.name}: its RL Zoo {RL_ZOO_ARGS} cannot be read ({exc})")
    args = args if isinstance(args, dict) else {}
    kwargs = dict(args.get("env_kwargs") or {})
    source = f"{args_file.parent.name}/{RL_ZOO_ARGS} (env_kwargs {kwargs})"
    try:
        import gymnasium

        env = gymnasium.make(str(args.get("env", "GripSelect-v0")), **kwargs)
        objects = env_objects(env)
        env.close()
    except Exception as exc:  # its dataset moved or gone: the record cannot be read here
        return Recorded(None, "", f"{path.name}: its RL Zoo env_kwargs {kwargs} do not make its "
                                  f"environment here ({type(exc).__name__}: {exc})")  # fmt: skip
    return Recorded(objects, source)


class _ZooLoader(yaml.SafeLoader):
    """YAML's safe loader that also reads the ``OrderedDict`` RL Zoo writes ``args.yml`` as."""


def _ordered_dict(loader: yaml.SafeLoader, node: yaml.Node) -> dict[str, Any]:
    (pairs,) = loader.construct_sequence(node, deep=True)
    return {str(key): value for key, value in pairs}


_ZooLoader.add_constructor("tag:yaml.org,2002:python/object/apply:collections.OrderedDict",
                           _ordered_dict)  # fmt: skip


def recorded_function(function: Any, spec: str) -> Recorded:
    """A function's or class's ``trained_on`` attribute (object ids; empty: learns nothing)."""
    objects = getattr(function, RECORD_KEY, None)
    if objects is None:
        return Recorded(None, "", f"{spec}: no record of its training objects (give the "
                                  f"function a {RECORD_KEY} attribute: the object ids it learnt "
                                  f"from, () for none)")  # fmt: skip
    if isinstance(objects, str | bytes) or not isinstance(objects, Iterable):
        raise ValueError(f"{spec}.{RECORD_KEY} must be a list of object ids, got {objects!r}")
    return Recorded(tuple(map(str, objects)), f"{spec}.{RECORD_KEY}")


# ------------------------------------------------------------------ the training budget
BUDGET_KEY = "budget"
NOT_RECORDED = "not recorded"


def recorded_budget(path: Path) -> dict[str, Any]:
    """A method file's training budget: ``NAME.json``'s ``budget`` entry, else an SB3 zip's
    environment steps, else not recorded. ``text`` says it in words."""
    info = _json(path.with_suffix(".json")) if path.with_suffix(".json").is_file() else None
    budget = info.get(BUDGET_KEY) if isinstance(info, dict) else None
    if isinstance(budget, dict):
        return {**budget, "text": budget_text(budget)}
    if path.suffix.lower() == ".zip":
        steps = _sb3_steps(path)
        if steps is not None:
            return {"environment_steps": steps, "text": budget_text({"environment_steps": steps})}
    return {"text": NOT_RECORDED}


def function_budget(function: Any) -> dict[str, Any]:
    """A function's or class's ``training_budget`` attribute (a dict with ``environment_steps``
    or ``transitions``/``episodes``, or a sentence), else not recorded."""
    budget = getattr(function, "training_budget", None)
    if isinstance(budget, dict):
        return {**budget, "text": budget_text(budget)}
    return {"text": str(budget) if budget is not None else NOT_RECORDED}


def budget_text(budget: dict[str, Any]) -> str:
    """``20,000 environment steps``, ``7,640 transitions (7,640 episodes) of SOURCE`` or, for a
    supervised learner, ``8,429 labelled grips of 382 objects (42,145 recorded trials)``."""
    parts = []
    if budget.get("grips") is not None:
        trials = budget.get("trials")
        parts.append(f"{int(budget['grips']):,} labelled grips of {int(budget['objects']):,} "
                     f"objects" + (f" ({int(trials):,} recorded trials)" if trials else ""))
    if budget.get("environment_steps") is not None:
        parts.append(f"{int(budget['environment_steps']):,} environment steps")
    if budget.get("transitions") is not None:
        extra = [f"{int(budget[k]):,} {k.replace('_', ' ')}"
                 for k in ("episodes", "gradient_steps") if budget.get(k) is not None]
        parts.append(f"{int(budget['transitions']):,} transitions"
                     + (f" ({', '.join(extra)})" if extra else "")
                     + (f" of {budget['source']}" if budget.get("source") else ""))  # fmt: skip
    return "; ".join(parts) or NOT_RECORDED


def _sb3_steps(path: Path) -> int | None:
    """The environment steps an SB3 zip was trained for (its saved ``num_timesteps``)."""
    import zipfile

    try:
        with zipfile.ZipFile(path) as archive:
            data = json.loads(archive.read("data"))
    except (OSError, KeyError, ValueError, zipfile.BadZipFile):
        return None
    steps = data.get("num_timesteps") if isinstance(data, dict) else None
    return int(steps) if isinstance(steps, int) else None


# ------------------------------------------------------------------ the check
def check_training(records: Sequence[Recorded], specs: Sequence[str],
                   held_out: Sequence[str]) -> dict[str, Any]:  # fmt: skip
    """The leaderboard's ``training`` entry of a method (its runs' records); ValueError when a
    run was trained on a held-out object of the split."""
    test = set(held_out)
    for record, spec in zip(records, specs, strict=True):
        seen = sorted(test.intersection(record.objects or ()))
        if seen:
            shown = ", ".join(seen[:3]) + (f" and {len(seen) - 3} more" if len(seen) > 3 else "")
            raise ValueError(
                f"{spec} was trained on {len(seen)} of the split's {len(test)} held-out objects "
                f"({shown}; from {record.source}): its scores would be in-sample; fit it on the "
                f"split's training objects (grip-env train --split train; an agent: "
                f"GripSelect-v0 with split='train')")  # fmt: skip
    unrecorded = [r.missing for r in records if r.objects is None]
    if unrecorded:
        return {"status": "unrecorded",
                "note": "training objects not recorded, so the benchmark cannot check that it "
                        f"never saw a held-out object: {'; '.join(unrecorded)}"}  # fmt: skip
    seen = sorted({o for r in records for o in r.objects or ()})
    return {"status": "checked", "objects": len(seen),
            "note": f"trained on {len(seen)} recorded objects, none of the {len(test)} held out "
                    f"(from {', '.join(sorted({r.source for r in records}))})"}  # fmt: skip


def _json(path: Path) -> Any:
    try:
        return json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError):
        return None
