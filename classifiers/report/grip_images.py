"""What an image evaluator sees: grips' images with their labels, and occlusion maps over them."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from numpy.typing import NDArray
from sklearn.pipeline import Pipeline

from classifiers.learners.grip_images import CHANNELS, GripImages
from classifiers.learners.occlusion import grip_occlusion_maps
from grip_env.drawing import save_figure

#: Each channel's colour in a composite (RGB, added over a white ground).
CHANNEL_COLOURS = {"silhouette": (0.45, 0.45, 0.45), "approach": (0.35, 0.55, 0.95),
                   "contacts": (0.95, 0.15, 0.10)}


def composite(image: NDArray[np.floating], channels: Sequence[str] = CHANNELS
              ) -> NDArray[np.float64]:
    """One grip's image (C, H, W) as RGB (H, W, 3): the silhouette grey, the fingers' approach
    blue over it, the contacts red on top, on white."""
    rgb = np.ones((*image.shape[1:], 3))
    for name in ("silhouette", "approach", "contacts"):
        if name in channels:
            alpha = np.clip(image[list(channels).index(name)], 0.0, 1.0)[..., None]
            strength = 0.55 if name == "approach" else 1.0
            rgb = rgb * (1 - strength * alpha) + strength * alpha * np.array(CHANNEL_COLOURS[name])
    return rgb


def choose_grips(grips: pd.DataFrame, count: int = 8, seed: int = 0) -> pd.DataFrame:
    """A seeded choice of ``count`` grips from distinct objects, half held and half slipped
    (``success``), held first."""
    rng = np.random.default_rng(seed)
    one_per_object = grips.iloc[rng.permutation(len(grips))].drop_duplicates("object_id")
    held = one_per_object[one_per_object["success"].astype(bool)]
    slipped = one_per_object[~one_per_object["success"].astype(bool)]
    half = count // 2
    return pd.concat([held.head(count - half), slipped.head(half)])


def grip_images_figure(grips: pd.DataFrame, transformer: GripImages | None = None,
                       columns: int = 4) -> Figure:
    """Each grip's image (``transformer``'s, default :class:`GripImages`) in its hand's frame,
    titled with its object, label (success, rate) and robustness; axes in mm from the palm."""
    transformer = transformer or GripImages()
    images = transformer.fit_transform(grips)
    titles = [_label(grip) for _, grip in grips.iterrows()]
    fig = _panels(len(grips), columns)
    half = transformer.size_px * transformer.mm_per_px / 2
    for ax, image, title in zip(fig.axes, images, titles, strict=False):
        ax.imshow(composite(image, transformer.channels), extent=(-half, half, -half, half),
                  interpolation="nearest")
        ax.set_title(title, fontsize=7)
        ax.tick_params(labelsize=6)
    fig.suptitle(f"What the image evaluator sees: {transformer.size_px} px at "
                 f"{transformer.mm_per_px:g} mm/px, palm centre at (0, 0), thumb force up; "
                 "grey object, blue fingers' approach, red contacts", fontsize=8)
    fig.supxlabel("hand x (mm)", fontsize=8)
    fig.supylabel("hand y: the thumb's force (mm)", fontsize=8)
    fig.tight_layout()
    return fig


def draw_grip_images(grips: pd.DataFrame, path: str | Path,
                     transformer: GripImages | None = None, columns: int = 4) -> Path:
    """:func:`grip_images_figure` written to ``path`` (PNG)."""
    return save_figure(grip_images_figure(grips, transformer, columns), path, dpi=110)


def occlusion_figure(images: NDArray[np.floating], maps: NDArray[np.floating],
                     titles: Sequence[str], channels: Sequence[str] = CHANNELS) -> Figure:
    """Each image beside its occlusion map (drop in predicted success when a patch is greyed):
    red where hiding the pixels lowers the prediction, blue where it raises it."""
    fig = Figure(figsize=(2.6 * len(images) + 0.8, 5.4), layout="constrained")
    axes = fig.subplots(2, len(images), squeeze=False)
    limit = float(np.max(np.abs(maps))) or 1.0
    for k, (image, drop, title) in enumerate(zip(images, maps, titles, strict=True)):
        axes[0, k].imshow(composite(image, channels), interpolation="nearest")
        axes[0, k].set_title(title, fontsize=6.5)
        shown = axes[1, k].imshow(drop, cmap="RdBu_r", vmin=-limit, vmax=limit)
        axes[1, k].imshow(image[list(channels).index("silhouette")] if "silhouette" in channels
                          else np.zeros(drop.shape), cmap="Greys", alpha=0.15)
        for ax in axes[:, k]:
            ax.set_xticks([])
            ax.set_yticks([])
    axes[0, 0].set_ylabel("the grip's image", fontsize=8)
    axes[1, 0].set_ylabel("occlusion map", fontsize=8)
    fig.colorbar(shown, ax=axes[1, :].tolist(), shrink=0.8, label="drop in P(success)")
    return fig


def grip_occlusion_figure(pipeline: Pipeline, grips: pd.DataFrame, **options: object) -> Figure:
    """:func:`occlusion_figure` of ``grips`` under a fitted ``pipeline`` that starts by drawing
    them (:func:`~classifiers.learners.occlusion.grip_occlusion_maps`, with ``options``), each
    titled with its label and the pipeline's predicted success."""
    images, maps = grip_occlusion_maps(pipeline, grips, **options)
    predicted = np.asarray(pipeline.predict_proba(grips))[:, 1]
    titles = [f"{_label(grip)}\npredicted {p:.2f}"
              for (_, grip), p in zip(grips.iterrows(), predicted, strict=True)]
    drawer = next(step for _, step in pipeline.steps if isinstance(step, GripImages))
    return occlusion_figure(images, maps, titles, tuple(drawer.channels))


def _panels(count: int, columns: int) -> Figure:
    rows = int(np.ceil(count / columns))
    fig = Figure(figsize=(2.4 * columns, 2.5 * rows + 0.3))
    axes = np.atleast_1d(fig.subplots(rows, columns)).ravel()
    for ax in axes[count:]:
        ax.remove()
    return fig


def _label(grip: pd.Series) -> str:
    """Object, label and how the label came about: "success: held in 80% of trials, 96 g"."""
    outcome = "success" if bool(grip["success"]) else "failure"
    rate = (f": held in {grip['success_rate']:.0%} of trials" if "success_rate" in grip
            and pd.notna(grip["success_rate"]) else "")
    robust = (f", {grip['robustness_mean']:.0f} g" if "robustness_mean" in grip
              and pd.notna(grip["robustness_mean"]) else "")
    return f"{grip['object_id']}\n{outcome}{rate}{robust}"
