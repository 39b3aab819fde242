"""The standard dataset shipped with grip-env, and the names a ``--data`` option accepts.

>>> from grip_env.datasets import load_standard, standard_path   # doctest: +SKIP
>>> grips = load_standard()              # the DataFrame, .attrs as grip_env.dataset.load gives
>>> folder = standard_path()             # for grip_env.dataset.load, validate, every --data

``--data standard`` on the command line and ``gymnasium.make("GripSelect-v0", data="standard")``
mean :func:`standard_path`. Its recipe is ``configs/standard.yaml``; its card is
``docs/dataset.md``.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from grip_env.label_model import LABEL_MODEL

#: The name that stands for the shipped dataset wherever a dataset folder is asked for.
STANDARD = "standard"
#: How to make the standard dataset from its recipe.
REGENERATE = "grip-env generate --config configs/standard.yaml --out DIR, then give DIR"
#: Where the package keeps it.
SHIPPED = Path(__file__).parent / "data" / STANDARD


def standard_path() -> Path:
    """The folder of the shipped standard dataset (inside the installed package).

    Raises:
        ValueError: this install holds no finished standard dataset, or it was labelled by
            another label model than this code's (say how to regenerate it).
    """
    _check_standard(SHIPPED)
    return SHIPPED


def load_standard(verify: bool = True) -> pd.DataFrame:
    """All grips of the standard dataset, as :func:`grip_env.dataset.load` returns them."""
    from grip_env.dataset import load

    return load(standard_path(), verify=verify)


def resolve_data(data: str | Path) -> Path:
    """A dataset folder from what a user gave: :data:`STANDARD` is :func:`standard_path`,
    anything else a path (give a local folder named ``standard`` by its absolute path)."""
    return standard_path() if str(data) == STANDARD else Path(data)


def _check_standard(folder: Path) -> None:
    """Raise unless ``folder`` holds a dataset of this code's label model."""
    from grip_env.dataset import dataset_label_model, dataset_manifest
    from grip_env.dataset.manifest import MANIFEST_FILE

    if not (folder / MANIFEST_FILE).is_file():
        raise ValueError(f"this grip-env install holds no standard dataset ({folder} is empty); "
                         f"make one with: {REGENERATE}")
    found = dataset_label_model(folder)
    if found != LABEL_MODEL:
        raise ValueError(f"the shipped standard dataset was labelled by label model {found!r}, "
                         f"this grip-env's is {LABEL_MODEL!r}; regenerate it with: {REGENERATE}")
    manifest = dataset_manifest(folder)
    if not manifest.get("complete", False):
        done, total = len(manifest["shards"]), len(manifest["objects"])
        raise ValueError(f"the shipped standard dataset is unfinished ({done} of {total} objects "
                         f"generated); finish it with: {REGENERATE}")
