"""What an image evaluator sees: grips' images with their labels, and occlusion maps over them."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from numpy.typing import NDArray

from classifiers.learners.grip_images import CHANNELS, GripImages
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
    one_per_object = grips.loc[rng.permutation(len(grips))].drop_duplicates("object_id")
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
    fig = Figure(figsize=(2.2 * len(images), 4.6))
    axes = fig.subplots(2, len(images), squeeze=False)
    limit = float(np.max(np.abs(maps))) or 1.0
    for k, (image, drop, title) in enumerate(zip(images, maps, titles, strict=True)):
        axes[0, k].imshow(composite(image, channels), interpolation="nearest")
        axes[0, k].set_title(title, fontsize=7)
        shown = axes[1, k].imshow(drop, cmap="RdBu_r", vmin=-limit, vmax=limit)
        axes[1, k].imshow(image[list(channels).index("silhouette")] if "silhouette" in channels
                          else np.zeros(drop.shape), cmap="Greys", alpha=0.15)
        for ax in axes[:, k]:
            ax.set_xticks([])
            ax.set_yticks([])
    fig.colorbar(shown, ax=axes[1, :].tolist(), shrink=0.8, label="drop in P(success)")
    return fig


def _panels(count: int, columns: int) -> Figure:
    rows = int(np.ceil(count / columns))
    fig = Figure(figsize=(2.4 * columns, 2.5 * rows + 0.3))
    axes = np.atleast_1d(fig.subplots(rows, columns)).ravel()
    for ax in axes[count:]:
        ax.remove()
    return fig


def _label(grip: pd.Series) -> str:
    outcome = "held" if bool(grip["success"]) else "slipped"
    rate = (f" {grip['success_rate']:.0%}" if "success_rate" in grip
            and pd.notna(grip["success_rate"]) else "")
    robust = (f", {grip['robustness_mean']:.2f} g" if "robustness_mean" in grip
              and pd.notna(grip["robustness_mean"]) else "")
    return f"{grip['object_id']}\n{outcome}{rate}{robust}"
