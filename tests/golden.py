"""The golden trials: a fixed set of planned grips whose outcomes pin the label model.

    python -m tests.golden            # compare with the recording (what tests/test_golden.py does)
    python -m tests.golden --record   # renew the recording, after bumping LABEL_MODEL

Each default object of ``OBJECTS`` gives its ``GRIPS`` best grips by Q_C and its worst (so that
failures are pinned too); their plans are stored
in the recording, so that the golden test pins the simulator (scene, hand, controller, draws,
ramp, judgement) and not the planner. Every grip runs ``TRIALS`` trials with ``SEED`` under the
default config.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import pandas as pd

from grip_env.config import Config
from grip_env.objects import PlanarObject, load_object_set
from grip_env.sim import LABEL_MODEL, run_trial_outcomes
from grip_env.sim.trial import PLAN_COLUMNS

RECORDING = Path(__file__).parent / "data" / "golden_outcomes.json"
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


def run(grips: pd.DataFrame) -> list[dict]:
    """Every golden trial's pinned outcome, in recording order."""
    records = []
    for name, group in grips.groupby("object_id", sort=False):
        outcomes = run_trial_outcomes(_object(str(name)), group, Config(), trials=TRIALS,
                                      seed=SEED)
        for row in outcomes.itertuples(index=False):
            record = {"grip_id": group.loc[row.grip, "grip_id"], "trial": int(row.trial)}
            for field in PINNED:
                value = getattr(row, field)
                record[field] = bool(value) if field in ("success", "held") else (
                    int(value) if field == "steps" else float(value))
            records.append(record)
    return records


def record() -> None:
    grips = plans()
    RECORDING.write_text(json.dumps({
        "label_model": LABEL_MODEL, "seed": SEED, "trials": TRIALS,
        "grips": grips.to_dict(orient="records"), "outcomes": run(grips)}, indent=1) + "\n")


def recording() -> dict:
    """The stored recording."""
    return json.loads(RECORDING.read_text())


def differences(stored: dict) -> list[str]:
    """Lines naming every pinned outcome that differs from the recording (none: it holds)."""
    lines = []
    if stored["label_model"] != LABEL_MODEL:
        lines.append(f"the recording is of label model {stored['label_model']!r}, the code's is "
                     f"{LABEL_MODEL!r}: renew it with python -m tests.golden --record")
    now = run(pd.DataFrame(stored["grips"]))
    for old, new in zip(stored["outcomes"], now, strict=True):
        for field in PINNED:
            if old[field] != new[field]:
                lines.append(f"{old['grip_id']} trial {old['trial']}: {field} "
                             f"{old[field]!r} -> {new[field]!r}")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record", action="store_true", help="renew the recording")
    if parser.parse_args().record:
        record()
        print(f"recorded {len(recording()['outcomes'])} trials for {LABEL_MODEL}")
        return
    lines = differences(recording())
    print("\n".join(lines) or f"every golden trial matches label model {LABEL_MODEL}")
    sys.exit(1 if lines else 0)


if __name__ == "__main__":
    main()
