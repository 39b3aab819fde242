"""Resolution sweep of rendered perception against the polygon on the default objects.

Usage: python scripts/perception_sweep.py [RESOLUTION ...] (default 128 256 512 1024); prints a
Markdown table per resolution, then one per object and resolution.
"""

from __future__ import annotations

import sys

import pandas as pd

from grip_env.objects import load_object_set
from grip_env.perception_fidelity import resolution_sweep, sweep_summary


def markdown(frame: pd.DataFrame) -> str:
    """A DataFrame as a Markdown table (index first when it is named)."""
    shown = frame.reset_index() if frame.index.name else frame
    cells = [[f"{v:.3g}" if isinstance(v, float) else str(v) for v in row]
             for row in shown.itertuples(index=False)]
    lines = ["| " + " | ".join(map(str, shown.columns)) + " |",
             "|" + "---|" * len(shown.columns)]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in cells])


def main(argv: list[str]) -> None:
    resolutions = [int(a) for a in argv] or [128, 256, 512, 1024]
    table = resolution_sweep(load_object_set("default"), resolutions)
    print(markdown(sweep_summary(table)))
    print()
    print(markdown(table))


if __name__ == "__main__":
    main(sys.argv[1:])
