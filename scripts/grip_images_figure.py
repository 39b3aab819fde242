"""Draw the docs' figure of what the image evaluator sees: eight grips of the standard dataset
(a seeded choice, four that held and four that slipped, each of another object), as
:class:`~classifiers.learners.grip_images.GripImages` draws them, with their labels.

Usage: python scripts/grip_images_figure.py [OUT] (default docs/_static/grip_images.png)
"""

from __future__ import annotations

import sys
from pathlib import Path

from classifiers.learners.grip_images import load_with_contours
from classifiers.report.grip_images import choose_grips, draw_grip_images
from grip_env.datasets import standard_path

DEFAULT_OUT = Path(__file__).resolve().parents[1] / "docs" / "_static" / "grip_images.png"


def main(argv: list[str]) -> None:
    out = Path(argv[0]) if argv else DEFAULT_OUT
    grips = load_with_contours(standard_path())
    print(draw_grip_images(choose_grips(grips, count=8, seed=0), out))


if __name__ == "__main__":
    main(sys.argv[1:])
