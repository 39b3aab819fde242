"""Resolution sweep of rendered perception against the polygon on the default objects.

Usage: python scripts/perception_sweep.py [RESOLUTION ...] (default 128 256 512 1024); prints a
Markdown table per resolution and per object.
"""

from __future__ import annotations

import sys

from grip_env.objects import load_object_set
from grip_env.perception.fidelity import resolution_sweep, sweep_summary


def main(argv: list[str]) -> None:
    resolutions = [int(a) for a in argv] or [128, 256, 512, 1024]
    table = resolution_sweep(load_object_set("default"), resolutions)
    print(sweep_summary(table).to_markdown(floatfmt=".3g"))
    print()
    print(table.to_markdown(index=False, floatfmt=".3g"))


if __name__ == "__main__":
    main(sys.argv[1:])
