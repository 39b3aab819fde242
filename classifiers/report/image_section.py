"""The report's section on the image models (the study's ``images/`` stage): their grouped CV
beside the measures' learner, the paired differences, the picks by family, which measure the
network's score resembles, and its occlusion maps."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from classifiers.report.answers import image_family_rows, read_answers
from classifiers.report.document import Report, frame_of_intervals

RESULT = Path("images") / "images.json"
SHOWN = ["roc_auc", "balanced_accuracy", "brier", "top1_success"]
OCCLUSION = Path("images") / "occlusion.npz"
OCCLUSION_CAPTION = ("Occlusion maps of the image-only network on held-out grips (the three it "
                     "scores highest, then the three lowest): above, each grip's image (grey "
                     "object, blue fingers' approach, red contacts, thumb force up); below, the "
                     "drop in its predicted success when an 8-pixel grey square hides the "
                     "pixels (red: hiding them lowers it).")


def image_section(report: Report, out: Path, fig_dir: Path) -> None:
    """The section, or "Not run." when the study has no image stage result."""
    report.heading("Image models: what the twelve measures miss")
    path = out / RESULT
    result = json.loads(path.read_text()) if path.is_file() else None
    if not result or "cv" not in result:
        report.text(f"Not run{': ' + result['skipped'] if result else ''}.")
        return
    cv = result["cv"]
    report.table(frame_of_intervals(cv["models"], SHOWN),
                 caption="Image models and the measures' learner on the same grouped folds "
                         "(mean and 95% interval).")
    report.table(frame_of_intervals(cv["paired_difference"], SHOWN),
                 caption=f"Paired difference against {cv['reference']} on the twelve measures "
                         f"(same folds and seeds).")
    report.text(fit_time_line(cv["fit_seconds"], cv["n_grips"], cv["folds"]))
    rows = image_family_rows(read_answers(out) or {})
    if rows:
        report.table(pd.DataFrame(rows), caption="Top-1 success difference on the held-out "
                                                 "objects of each family (paired bootstrap).")
    report.text(resemblance_line(result.get("resemblance")))
    if (out / OCCLUSION).is_file():
        path = draw_occlusion(out / OCCLUSION, fig_dir / "occlusion.png")
        report.figure(str(path.relative_to(out)), OCCLUSION_CAPTION)


def draw_occlusion(record: Path, path: Path) -> Path:
    """The occlusion figure of the stage's record (its images, maps and titles) as ``path``."""
    from classifiers.report.grip_images import occlusion_figure
    from grip_env.drawing import save_figure

    with np.load(record) as found:
        figure = occlusion_figure(found["images"], found["maps"], found["titles"].tolist(),
                                  found["channels"].tolist())  # fmt: skip
    path.parent.mkdir(parents=True, exist_ok=True)
    return save_figure(figure, path, dpi=110)


def fit_time_line(seconds: dict[str, dict[str, Any]], grips: int, folds: int) -> str:
    """One sentence: each model's CPU seconds a fit of a training fold (mean, longest), and the
    wall time beside it (on a shared machine, CPU is what the fit costs)."""
    shown = ", ".join(f"{name} {found['cpu_mean']:.1f} s CPU (longest {found['cpu_max']:.1f} s; "
                      f"wall {found['mean']:.1f} s)" for name, found in seconds.items())
    return (f"Fit of a training fold (about {round(grips * (folds - 1) / folds):,} grips, one "
            f"thread): {shown}.")


def resemblance_line(resemblance: dict[str, Any] | None) -> str:
    """For the paper's authors: which measure the image network's score resembles, if any."""
    if not resemblance or resemblance.get("closest") is None:
        return "The image network's resemblance to the measures was not computed."
    rho = resemblance["spearman"]
    closest = resemblance["closest"]
    others = ", ".join(f"{m} {r:+.2f}" for m, r in sorted(rho.items(), key=lambda kv: -abs(kv[1]))
                       [1:4])  # fmt: skip
    strength = abs(rho[closest])
    resembles = ("resembles" if strength >= 0.5 else "resembles none closely; the nearest is"
                 if strength < 0.3 else "resembles in part")  # fmt: skip
    return (f"Which measure the image network resembles: its score ({resemblance['model']}, on "
            f"the {resemblance['grips']:,} held-out grips) {resembles} {closest} (Spearman "
            f"{rho[closest]:+.2f}; next {others}).")
