"""The golden trials: a fixed set of planned grips whose outcomes pin each engine's label model.

    python -m tests.golden                           # compare with the recording (the test does)
    python -m tests.golden --record                  # renew it, after bumping LABEL_MODEL
    python -m tests.golden --engine mujoco --record  # MuJoCo's, after bumping MUJOCO_LABEL_MODEL

Each default object of ``OBJECTS`` gives its ``GRIPS`` best grips by Q_C and its worst (so that
failures are pinned too); their plans are stored
in the recording, so that the golden test pins the simulator (scene, hand, controller, draws,
ramp, judgement) and not the planner. Every grip runs ``TRIALS`` trials with ``SEED`` under the
default config. MuJoCo's recording (``sim.engine: mujoco``) runs the grips of PyBullet's, so both
pin the same trials; each names its engine's label model (``grip_env.label_model``) and version.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import pandas as pd

from grip_env.config import Config
from grip_env.dataset.manifest import engine_record
from grip_env.label_model import label_model_for
from grip_env.objects import PlanarObject, load_object_set
from grip_env.sim import run_trial_outcomes
from grip_env.sim.trial import PLAN_COLUMNS

#: Each engine's recording (PyBullet's plans the grips; the others run the same ones).
RECORDINGS = {"pybullet": Path(__file__).parent / "data" / "golden_outcomes.json",
              "mujoco": Path(__file__).parent / "data" / "golden_outcomes_mujoco.json"}
RECORDING = RECORDINGS["pybullet"]
#: Polygons and two curved outlines (their simulated shapes are simplified).
OBJECTS = ("pentagon", "trapezoid", "rectangle", "hexagon", "ellipse", "bean")
GRIPS = 2
TRIALS = 3
SEED = 7
#: The outcome fields pinned, each compared exactly.
PINNED = ("robustness", "success", "held", "friction", "mass_kg", "drift_mm", "rotation_deg",
          "steps")


def _object(name: str) -> PlanarObject:
    return next(o for o in load_object_set("default") if o.name == name)


def plans() -> pd.DataFrame:
    """The golden grips, planned now (only ``--record`` plans; the test reads the recording)."""
    from grip_env.planning.pipeline import candidates

    rows = []
    for name in OBJECTS:
        table = candidates(_object(name)).sort_values("Q_C", kind="stable")
        picked = pd.concat([table.head(GRIPS), table.tail(1)])
        rows.append(picked[["object_id", "grip_id", *PLAN_COLUMNS]])
    return pd.concat(rows, ignore_index=True)


def run(grips: pd.DataFrame, engine: str = "pybullet") -> list[dict]:
    """Every golden trial's pinned outcome in ``engine``, in recording order."""
    records = []
    config = Config().override(sim={"engine": engine})
    for name, group in grips.groupby("object_id", sort=False):
        outcomes = run_trial_outcomes(_object(str(name)), group, config, trials=TRIALS,
                                      seed=SEED)
        for row in outcomes.itertuples(index=False):
            record = {"grip_id": group.loc[row.grip, "grip_id"], "trial": int(row.trial)}
            for field in PINNED:
                value = getattr(row, field)
                record[field] = bool(value) if field in ("success", "held") else (
                    int(value) if field == "steps" else float(value))
            records.append(record)
    return records


def record(engine: str = "pybullet") -> None:
    """Renew ``engine``'s recording (PyBullet's plans the grips again; another engine runs the
    grips of PyBullet's recording)."""
    grips = plans() if engine == "pybullet" else pd.DataFrame(recording()["grips"])
    stored = {"label_model": label_model_for(engine), "seed": SEED, "trials": TRIALS,
              "grips": grips.to_dict(orient="records"), "outcomes": run(grips, engine)}
    if engine != "pybullet":  # PyBullet's recording keeps the fields it was made with
        stored = {"engine": engine_record(engine), **stored}
    RECORDINGS[engine].write_text(json.dumps(stored, indent=1) + "\n")


def recording(engine: str = "pybullet") -> dict:
    """The stored recording of ``engine``."""
    return json.loads(RECORDINGS[engine].read_text())


def renew_command(engine: str) -> str:
    """The command that renews ``engine``'s recording."""
    flag = "" if engine == "pybullet" else f" --engine {engine}"
    return f"python -m tests.golden{flag} --record"


def differences(stored: dict, engine: str = "pybullet") -> list[str]:
    """Lines naming every pinned outcome that differs from the recording (none: it holds)."""
    lines = []
    expected = label_model_for(engine)
    if stored["label_model"] != expected:
        lines.append(f"the recording is of label model {stored['label_model']!r}, the code's is "
                     f"{expected!r}: renew it with {renew_command(engine)}")
    now = run(pd.DataFrame(stored["grips"]), engine)
    for old, new in zip(stored["outcomes"], now, strict=True):
        for field in PINNED:
            if old[field] != new[field]:
                lines.append(f"{old['grip_id']} trial {old['trial']}: {field} "
                             f"{old[field]!r} -> {new[field]!r}")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record", action="store_true", help="renew the recording")
    parser.add_argument("--engine", choices=sorted(RECORDINGS), default="pybullet",
                        help="the engine whose recording to renew or check")
    args = parser.parse_args()
    model = label_model_for(args.engine)
    if args.record:
        record(args.engine)
        print(f"recorded {len(recording(args.engine)['outcomes'])} trials for {model}")
        return
    lines = differences(recording(args.engine), args.engine)
    print("\n".join(lines) or f"every golden trial matches label model {model}")
    sys.exit(1 if lines else 0)


if __name__ == "__main__":
    main()
