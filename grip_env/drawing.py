"""Drawing objects, grasping regions and grips (the paper's figure style) with matplotlib."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from grip_env.objects import PlanarObject
from grip_env.perception.regions import Regions
from grip_env.planning.barrett import spread_axes

_FINGER_COLOURS = ("tab:blue", "tab:green", "tab:red")


def draw_object(ax: Axes, obj: PlanarObject, regions: Regions | None = None) -> None:
    """The object's contour and centroid, and its grasping regions with inward normals."""
    closed = np.vstack([obj.contour, obj.contour[:1]])
    ax.fill(closed[:, 0], closed[:, 1], color="0.88", zorder=0)
    ax.plot(closed[:, 0], closed[:, 1], color="0.35", lw=1.0, zorder=1)
    ax.plot(*obj.centroid, marker="+", color="k", ms=10, zorder=5)
    if regions is not None and len(regions):
        scale = 0.08 * obj.diameter
        for a, b, n in zip(regions.a, regions.b, regions.normal, strict=True):
            ax.plot([a[0], b[0]], [a[1], b[1]], color="tab:orange", lw=3.0, zorder=2)
            mid = (a + b) / 2
            ax.annotate("", mid + scale * n, mid, zorder=3,
                        arrowprops={"arrowstyle": "->", "color": "tab:orange", "lw": 1.0})
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")


def draw_grip(ax: Axes, grip: pd.Series, highlight: bool = True, label: str | None = None) -> None:
    """One configuration: contacts, real forces, finger lines to their spread axes, palm, foci."""
    alpha = 1.0 if highlight else 0.35
    contacts = np.array([[grip[f"p{i}_x"], grip[f"p{i}_y"]] for i in (1, 2, 3)])
    forces = np.array([[grip[f"f{i}_x"], grip[f"f{i}_y"]] for i in (1, 2, 3)])
    palm = np.array([grip["hand_x"], grip["hand_y"]])
    origins = [*spread_axes(palm, grip["hand_yaw"]), palm]  # finger lines start here
    triangle = np.vstack([contacts, contacts[:1]])
    ax.plot(triangle[:, 0], triangle[:, 1], ls=":", color="k", lw=0.8, alpha=alpha)
    arrow = 0.5 * float(np.mean([grip["e1"], grip["e2"], grip["e3"]]))
    for contact, force, origin, colour in zip(contacts, forces, origins, _FINGER_COLOURS,
                                               strict=True):
        ax.plot([origin[0], contact[0]], [origin[1], contact[1]], color=colour, lw=0.8,
                ls="--", alpha=alpha)
        ax.annotate("", contact + arrow * force, contact,
                    arrowprops={"arrowstyle": "-|>", "color": colour, "lw": 1.6, "alpha": alpha})
        ax.plot(*contact, "o", color=colour, ms=6, alpha=alpha)
    ax.plot(*palm, marker="s", color="k", ms=6, alpha=alpha)
    for key, marker in (("cg", "x"), ("cc", "*")):
        point = np.array([grip[f"{key}_x"], grip[f"{key}_y"]])
        if np.all(np.isfinite(point)):
            ax.plot(*point, marker=marker, color="purple", ms=8, alpha=alpha)
    if label:
        ax.text(*palm, f" {label}", fontsize=8, va="bottom", alpha=alpha)


def object_figure(
    obj: PlanarObject,
    regions: Regions | None = None,
    grips: pd.DataFrame | None = None,
    title: str | None = None,
) -> Figure:
    """A figure of one object with its regions and, optionally, grips (first one highlighted)."""
    fig = Figure(figsize=(5.5, 5.5))
    ax = fig.subplots()
    draw_object(ax, obj, regions)
    if grips is not None:
        for rank, (_, grip) in enumerate(grips.iterrows()):
            label = f"#{rank + 1} Q_C={grip['Q_C']:.2f}" if "Q_C" in grip else None
            draw_grip(ax, grip, highlight=rank == 0, label=label)
    ax.set_title(title or obj.name)
    ax.autoscale_view()
    ax.margins(0.15)
    fig.tight_layout()
    return fig


def save_figure(fig: Figure, path: str | Path, dpi: int = 120) -> Path:
    """Write a figure as PNG exactly at ``path`` (no suffix added), creating the folder.

    Figures here never touch pyplot's state.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi, format="png")
    return path
