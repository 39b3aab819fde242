"""An offline-RL baseline: d3rlpy's discrete CQL (or behaviour cloning) trained on a Minari export
of ``GripSelect-v0`` (``grip-env export minari``), never touching the environment.

>>> path = train_offline("grip-env/standard-uniform-v0", "runs/offline/cql.d3", steps=5000)
>>> # grip-env benchmark runs/offline/cql.d3   (scored on the standard split's held-out objects)

d3rlpy takes flat vector observations: the Dict observation becomes
``[features (K x F, row by row), mask (K)]`` (:func:`flat_observation`), the same at training
and at scoring. The Q-network is d3rlpy's default MLP encoder; at scoring, a slot's score is its
Q-value (CQL) and the padded slots are never scored (the benchmark scores the real candidates
only). Beside ``NAME.d3`` it writes ``NAME.json``: the objects of the export it learnt from
(``trained_on``, which the benchmark checks against its held-out objects), its training budget
(transitions, episodes and gradient steps) and the export's id, metadata and seed.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

ALGORITHMS: tuple[str, ...] = ("cql", "bc")
SUFFIX = ".d3"
EXTRA_HINT = "the offline extra: pip install 'grip-env[offline]' (minari, d3rlpy)"


@dataclass(frozen=True)
class Transitions:
    """The export's steps as flat arrays (d3rlpy's ``MDPDataset`` input)."""

    observations: NDArray[np.float32]
    actions: NDArray[np.int64]
    rewards: NDArray[np.float32]
    terminals: NDArray[np.float32]
    timeouts: NDArray[np.float32]
    episodes: int


def flat_observation(features: NDArray[Any], mask: NDArray[Any]) -> NDArray[np.float32]:
    """``(..., K, F)`` features and ``(..., K)`` mask as one ``(..., K * F + K)`` vector."""
    features = np.asarray(features, dtype=np.float32)
    flat = features.reshape(*features.shape[:-2], -1)
    return np.concatenate([flat, np.asarray(mask, dtype=np.float32)], axis=-1)


def require_d3rlpy() -> Any:
    """The ``d3rlpy`` module, or ValueError naming the extra to install."""
    import contextlib
    import io

    try:
        # d3rlpy logs its Shimmy registration on import (and the old gym it imports prints a
        # banner when gym_notices is installed): kept off the command's output
        with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
            import d3rlpy
    except ImportError as exc:
        raise ValueError(f"the offline baseline needs {EXTRA_HINT} ({exc})") from None
    return d3rlpy


def transitions(dataset: Any) -> Transitions:
    """Every step of a Minari dataset of ``GripSelect-v0`` episodes, flattened (the last
    observation of an episode, after its end, is dropped as d3rlpy expects)."""
    parts: dict[str, list[Any]] = {k: [] for k in ("obs", "act", "rew", "term", "time")}
    episodes = 0
    for episode in dataset.iterate_episodes():
        observations = episode.observations
        if not isinstance(observations, dict) or set(observations) != {"features", "mask"}:
            raise ValueError("the Minari dataset's observations are not GripSelect-v0's "
                             "Dict(features, mask)")  # fmt: skip
        steps = len(episode.actions)
        parts["obs"].append(flat_observation(observations["features"][:steps],
                                             observations["mask"][:steps]))  # fmt: skip
        parts["act"].append(np.asarray(episode.actions, dtype=np.int64))
        parts["rew"].append(np.asarray(episode.rewards, dtype=np.float32))
        parts["term"].append(np.asarray(episode.terminations, dtype=np.float32))
        parts["time"].append(np.asarray(episode.truncations, dtype=np.float32))
        episodes += 1
    if not episodes:
        raise ValueError("the Minari dataset holds no episode")
    obs, act, rew, term, time = (np.concatenate(parts[k]) for k in parts)
    return Transitions(obs, act, rew, term, time, episodes)


def load_export(dataset_id: str) -> tuple[Any, dict[str, Any]]:
    """A Minari export and grip-env's record in its metadata (ValueError when it has none)."""
    import minari

    from grip_env.offline.minari_export import RECORD_KEY

    try:
        dataset = minari.load_dataset(dataset_id)
    except (FileNotFoundError, ValueError) as exc:
        raise ValueError(f"cannot load Minari dataset {dataset_id!r}: {exc}") from None
    record = dataset.storage.metadata.get(RECORD_KEY)
    if not isinstance(record, dict) or not isinstance(record.get("objects"), list):
        raise ValueError(f"Minari dataset {dataset_id!r} has no grip-env record of its objects "
                         f"(write it with grip-env export minari)")  # fmt: skip
    return dataset, record


def make_algorithm(algorithm: str, batch_size: int, learning_rate: float) -> Any:
    """d3rlpy's discrete CQL or behaviour cloning, on the CPU."""
    d3rlpy = require_d3rlpy()
    if algorithm == "cql":
        config = d3rlpy.algos.DiscreteCQLConfig(batch_size=batch_size,
                                                learning_rate=learning_rate)  # fmt: skip
    elif algorithm == "bc":
        config = d3rlpy.algos.DiscreteBCConfig(batch_size=batch_size, learning_rate=learning_rate)
    else:
        raise ValueError(f"algorithm must be one of {ALGORITHMS}, got {algorithm!r}")
    return config.create(device="cpu:0")


def train_offline(
    dataset_id: str, out: str | Path, *, algorithm: str = "cql", steps: int = 5000,
    seed: int = 0, batch_size: int = 256, learning_rate: float = 3e-4,
) -> Path:
    """Train ``algorithm`` on the Minari export ``dataset_id`` for ``steps`` gradient steps
    (seeded, CPU); write ``out`` (a ``.d3`` file) and its record ``out.json``; return ``out``."""
    return train_offline_runs(dataset_id, [Path(out)], [seed], algorithm=algorithm, steps=steps,
                              batch_size=batch_size, learning_rate=learning_rate)[0]


def train_offline_runs(
    dataset_id: str, outs: Sequence[str | Path], seeds: Sequence[int], *, algorithm: str = "cql",
    steps: int = 5000, batch_size: int = 256, learning_rate: float = 3e-4,
) -> list[Path]:
    """:func:`train_offline` once per seed (``outs[i]`` for ``seeds[i]``), the export read once."""
    paths = [Path(out) for out in outs]
    if len(paths) != len(seeds) or not paths:
        raise ValueError(f"give one policy file per seed, got {len(paths)} for {len(seeds)}")
    for path in paths:
        if path.suffix != SUFFIX:
            raise ValueError(f"the policy file must end in {SUFFIX}, got {path}")
    if steps < 1:
        raise ValueError(f"steps must be >= 1, got {steps}")
    make_algorithm(algorithm, batch_size, learning_rate)  # checks the name before the long read
    d3rlpy = require_d3rlpy()
    dataset, record = load_export(dataset_id)
    data = transitions(dataset)
    for path, seed in zip(paths, seeds, strict=True):
        d3rlpy.seed(seed)
        mdp = d3rlpy.dataset.MDPDataset(
            data.observations, data.actions[:, None], data.rewards, data.terminals, data.timeouts,
            action_space=d3rlpy.ActionSpace.DISCRETE,
            action_size=int(dataset.storage.metadata["action_space"].n))  # fmt: skip
        algo = make_algorithm(algorithm, batch_size, learning_rate)
        algo.fit(mdp, n_steps=steps, n_steps_per_epoch=steps, show_progress=False,
                 logger_adapter=d3rlpy.logging.NoopAdapterFactory(), save_interval=steps + 1)
        path.parent.mkdir(parents=True, exist_ok=True)
        algo.save(str(path))
        path.with_suffix(".json").write_text(json.dumps(
            _record(dataset_id, dataset, record, data, algorithm, steps, seed, batch_size,
                    learning_rate), indent=2))  # fmt: skip
    return paths


def _record(dataset_id: str, dataset: Any, record: dict[str, Any], data: Transitions,
            algorithm: str, steps: int, seed: int, batch_size: int,
            learning_rate: float) -> dict[str, Any]:  # fmt: skip
    from classifiers.experiments.benchmark.provenance import RECORD_KEY, training_record

    d3rlpy = require_d3rlpy()
    budget = {"transitions": len(data.actions), "episodes": data.episodes,
              "gradient_steps": steps, "batch_size": batch_size,
              "source": f"Minari dataset {dataset_id}"}  # fmt: skip
    return {
        RECORD_KEY: training_record(record["objects"], record.get("dataset_sha256"),
                                    split=record.get("split"), minari_dataset=dataset_id),
        "budget": budget,
        "algorithm": f"d3rlpy {algorithm} (discrete)", "d3rlpy": d3rlpy.__version__,
        "seed": seed, "learning_rate": learning_rate,
        "behaviour_policy": record.get("behaviour_policy"),
        "observation": "flat: features (K x F, row by row) then mask (K)",
        "export": {"episodes_per_object": record.get("episodes_per_object"),
                   "seed": record.get("seed"), "dataset_sha256": record.get("dataset_sha256"),
                   "total_steps": int(dataset.total_steps)},
    }  # fmt: skip


def main(argv: Sequence[str] | None = None) -> None:
    """``python -m classifiers.experiments.offline_rl ID OUT_DIR --seeds 0 1 2``: one policy
    ``OUT_DIR/<algorithm>_s<seed>.d3`` (and its ``.json``) per seed."""
    import argparse

    parser = argparse.ArgumentParser(description=main.__doc__)
    parser.add_argument("dataset_id", help="the Minari export (grip-env export minari --id)")
    parser.add_argument("out_dir", type=Path)
    parser.add_argument("--algorithm", choices=ALGORITHMS, default="cql")
    parser.add_argument("--steps", type=int, default=5000, help="gradient steps")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--batch-size", type=int, default=256)
    parser.add_argument("--learning-rate", type=float, default=3e-4)
    args = parser.parse_args(argv)
    outs = [args.out_dir / f"{args.algorithm}_s{seed}{SUFFIX}" for seed in args.seeds]
    for path in train_offline_runs(args.dataset_id, outs, args.seeds, algorithm=args.algorithm,
                                   steps=args.steps, batch_size=args.batch_size,
                                   learning_rate=args.learning_rate):  # fmt: skip
        print(f"wrote {path} and {path.with_suffix('.json')}")


if __name__ == "__main__":
    main()
