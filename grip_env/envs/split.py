"""The environments' train/test split by object: :mod:`grip_env.dataset.split`, re-exported.

The split is decided in one place, the dataset layer, so the environments, the classifiers and
the RL selector hold out the same objects.
"""

from grip_env.dataset.split import SPLITS, Split, objects_in_split, split_objects

__all__ = ["SPLITS", "Split", "objects_in_split", "split_objects"]
