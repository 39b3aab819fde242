"""Drawing objects, grasping regions and grips (the paper's figure style) with matplotlib."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.backend_bases import RendererBase
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.legend_handler import HandlerTuple
from matplotlib.lines import Line2D
from matplotlib.text import Annotation, Text
from matplotlib.transforms import Bbox
from numpy.typing import NDArray

from grip_env.objects import PlanarObject
from grip_env.perception.regions import Regions
from grip_env.planning.barrett import spread_axes

_FINGER_COLOURS = ("tab:blue", "tab:green", "tab:red")
_FOCUS_COLOUR = "purple"
_REGION_COLOUR = "tab:orange"
#: Least gap (pixels) between two grips' labels.
LABEL_GAP_PX = 2.0


def draw_object(ax: Axes, obj: PlanarObject, regions: Regions | None = None) -> None:
    """The object's contour and centroid, and its grasping regions with inward normals."""
    closed = np.vstack([obj.contour, obj.contour[:1]])
    ax.fill(closed[:, 0], closed[:, 1], color="0.88", zorder=0)
    ax.plot(closed[:, 0], closed[:, 1], color="0.35", lw=1.0, zorder=1)
    ax.plot(*obj.centroid, marker="+", color="k", ms=10, zorder=5)
    if regions is not None and len(regions):
        scale = 0.08 * obj.diameter
        for a, b, n in zip(regions.a, regions.b, regions.normal, strict=True):
            ax.plot([a[0], b[0]], [a[1], b[1]], color=_REGION_COLOUR, lw=3.0, zorder=2)
            mid = (a + b) / 2
            ax.annotate("", mid + scale * n, mid, zorder=3,
                        arrowprops={"arrowstyle": "->", "color": _REGION_COLOUR, "lw": 1.0})
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")


def draw_grip(
    ax: Axes, grip: pd.Series, highlight: bool = True, label: str | None = None,
) -> Annotation | None:
    """One configuration: contacts, real forces, finger lines to their spread axes, palm, foci.

    ``label`` is written beside the palm, with a thin leader line to it; the label is returned
    (see :func:`separate_labels`)."""
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
            ax.plot(*point, marker=marker, color=_FOCUS_COLOUR, ms=8, alpha=alpha)
    if not label:
        return None
    return ax.annotate(label, palm, xytext=(6, 4), textcoords="offset points", fontsize=8,
                       va="bottom", alpha=alpha, zorder=6,
                       arrowprops={"arrowstyle": "-", "color": "0.4", "lw": 0.5,
                                   "shrinkA": 0, "shrinkB": 3})


def separate_labels(fig: Figure, labels: Sequence[Annotation], gap_px: float = LABEL_GAP_PX,
                    ) -> None:
    """Move labels (placed in offset points, as :func:`draw_grip` places them) down, one at a
    time in order, until each is at least ``gap_px`` from every label before it."""
    renderer = _renderer(fig)
    points_per_px = 72.0 / fig.dpi
    placed: list[Bbox] = []
    for label in labels:
        for _ in range(4 * len(labels) + 1):  # each move clears one earlier label
            box = label_extent(label, renderer)
            clash = next((b for b in placed if b.padded(gap_px).overlaps(box)), None)
            if clash is None:
                break
            x, y = label.xyann
            label.xyann = (x, y - (box.y1 - clash.y0 + gap_px + 0.5) * points_per_px)
        placed.append(label_extent(label, renderer))


def label_extent(label: Annotation, renderer: RendererBase | None = None) -> Bbox:
    """Where a label's text is drawn (display pixels), without its leader line."""
    renderer = renderer or _renderer(label.figure)  # type: ignore[arg-type]
    label.update_positions(renderer)
    return Text.get_window_extent(label, renderer)


def _renderer(fig: Figure) -> RendererBase:
    """The figure's renderer (an Agg canvas is attached to a bare Figure)."""
    if not hasattr(fig.canvas, "get_renderer"):
        FigureCanvasAgg(fig)
    return fig.canvas.get_renderer()  # type: ignore[attr-defined]


def grip_legend(best: str = "best grip by Q_C (opaque)", others: str | None = "other grips (faint)",
                regions: bool = False) -> tuple[list[Artist], list[str]]:
    """Handles and labels of a legend of what :func:`draw_grip` (and with ``regions``,
    :func:`draw_object`) draws; ``best``/``others`` name the opaque and the faint grips."""
    def line(**style: object) -> Line2D:
        return Line2D([], [], **style)  # type: ignore[arg-type]

    entries: list[tuple[Artist | tuple[Artist, ...], str]] = [
        (line(color="0.2", lw=2), best),
    ]
    if others:
        entries.append((line(color="0.2", lw=2, alpha=0.35), others))
    entries += [
        (tuple(line(marker="o", ls="", color=c) for c in _FINGER_COLOURS),
         "contacts of fingers 1, 2 and the thumb"),
        (line(color="0.2", lw=1.2, marker=">", ms=6), "finger forces (arrows)"),
        (line(color="0.2", lw=0.8, ls="--"), "finger lines from the spread axes (thumb: palm)"),
        (line(color="k", lw=0.8, ls=":"), "contact triangle"),
        (line(marker="s", ls="", color="k"), "palm centre (hand position)"),
        (line(marker="x", ls="", color=_FOCUS_COLOUR, ms=8), "grasp focus C_G"),
        (line(marker="*", ls="", color=_FOCUS_COLOUR, ms=9), "real focus C_C"),
    ]
    if regions:
        entries += [
            (line(color=_REGION_COLOUR, lw=3), "grasping region (arrow: inward normal)"),
            (line(marker="+", ls="", color="k", ms=10), "centroid"),
        ]
    return [handle for handle, _ in entries], [text for _, text in entries]  # type: ignore[misc]


def add_grip_legend(fig: Figure, handles: list[Artist], labels: list[str], ncol: int = 2,
                    fontsize: float = 7) -> float:
    """Put a grip legend along the top of ``fig``; returns the share of its height it takes."""
    legend = fig.legend(handles, labels, loc="upper center", ncol=ncol, fontsize=fontsize,
                        frameon=False, handler_map={tuple: HandlerTuple(ndivide=None)})
    height = legend.get_window_extent(_renderer(fig)).height
    return min(0.5, (height + 4.0) / fig.bbox.height)


def object_figure(
    obj: PlanarObject,
    regions: Regions | None = None,
    grips: pd.DataFrame | None = None,
    title: str | None = None,
) -> Figure:
    """A figure of one object with its regions and, optionally, grips (first one highlighted)."""
    with_grips = grips is not None and len(grips) > 0
    fig = Figure(figsize=(6.0, 7.0 if with_grips else 6.3))
    ax = fig.subplots()
    draw_object(ax, obj, regions)
    labels: list[Annotation] = []
    if grips is not None:
        for rank, (_, grip) in enumerate(grips.iterrows()):
            label = f"#{rank + 1} Q_C={grip['Q_C']:.2f}" if "Q_C" in grip else None
            text = draw_grip(ax, grip, highlight=rank == 0, label=label)
            if text is not None:
                labels.append(text)
    ax.set_title(title or obj.name)
    ax.autoscale_view()
    ax.margins(0.15)
    if with_grips:
        handles, names = grip_legend(others="next grips (faint)" if len(grips) > 1 else None,
                                     regions=regions is not None)
    else:
        handles, names = grip_legend(regions=True)
        handles, names = handles[-2:], names[-2:]
    top = add_grip_legend(fig, handles, names)
    fig.tight_layout(rect=(0, 0, 1, 1 - top))
    separate_labels(fig, labels)
    return fig


def trial_figure(rows: Sequence[tuple[str, Sequence[tuple[str, NDArray[np.uint8] | None]]]],
                 title: str | None = None) -> Figure:
    """Rows of camera frames, each row a trial (its title above it), each frame a phase (its
    title above it); a frame of None is a phase the trial did not reach (drawn blank)."""
    columns = max((len(frames) for _, frames in rows), default=1)
    heading = 0.35 if title else 0.0
    fig = Figure(figsize=(2.9 * columns, 2.75 * len(rows) + heading), layout="constrained")
    ratios = ([heading] if title else []) + [2.75] * len(rows)
    panels = list(fig.subfigures(len(ratios), 1, height_ratios=ratios, squeeze=False)[:, 0])
    if title:
        panels.pop(0).suptitle(title, fontsize=10, fontweight="bold")
    for panel, (row_title, frames) in zip(panels, rows, strict=True):
        panel.suptitle(row_title, fontsize=9)
        axes = panel.subplots(1, columns, squeeze=False)[0]
        for ax in axes:
            ax.set_axis_off()
        for ax, (phase, frame) in zip(axes, frames, strict=False):
            ax.set_title(phase, fontsize=8)
            if frame is not None:
                ax.imshow(frame)
            else:
                ax.imshow(np.full((3, 4, 3), 255, dtype=np.uint8))
                ax.text(0.5, 0.5, "not reached", ha="center", va="center",
                        transform=ax.transAxes, fontsize=8, color="0.4")
    return fig


def save_figure(fig: Figure, path: str | Path, dpi: int = 120) -> Path:
    """Write a figure as PNG exactly at ``path`` (no suffix added), creating the folder.

    Figures here never touch pyplot's state.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi, format="png")
    return path
