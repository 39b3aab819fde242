"""Gymnasium environments for choosing grips: ``GripSelect-v0`` and ``GripAccept-v0``.

>>> import gymnasium, grip_env
>>> env = gymnasium.make("GripSelect-v0", data="data/grips")   # replay a dataset
>>> env = gymnasium.make("GripSelect-v0")                      # live PyBullet, default objects

The classes load on first use, so ``import grip_env`` (which registers the ids) stays light.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

from grip_env.envs.registration import ENV_IDS, register_envs

if TYPE_CHECKING:
    from grip_env.dataset.split import objects_in_split, split_objects
    from grip_env.envs.accept import GripAcceptEnv
    from grip_env.envs.backends import LiveBackend, OutcomeBackend, ReplayBackend
    from grip_env.envs.core import GripEnvBase
    from grip_env.envs.observation import NORMALIZATIONS, CandidateSet, FeatureScaler
    from grip_env.envs.select import GripSelectEnv

_LAZY = {
    "GripAcceptEnv": "accept",
    "LiveBackend": "backends",
    "OutcomeBackend": "backends",
    "ReplayBackend": "backends",
    "GripEnvBase": "core",
    "NORMALIZATIONS": "observation",
    "CandidateSet": "observation",
    "FeatureScaler": "observation",
    "GripSelectEnv": "select",
    # the split by object is the dataset layer's (one split for envs, learners and selector)
    "objects_in_split": "grip_env.dataset.split",
    "split_objects": "grip_env.dataset.split",
}

__all__ = [
    "ENV_IDS",
    "NORMALIZATIONS",
    "CandidateSet",
    "FeatureScaler",
    "GripAcceptEnv",
    "GripEnvBase",
    "GripSelectEnv",
    "LiveBackend",
    "OutcomeBackend",
    "ReplayBackend",
    "objects_in_split",
    "register_envs",
    "split_objects",
]


def __getattr__(name: str) -> Any:
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module = _LAZY[name]
    return getattr(import_module(module if "." in module else f"grip_env.envs.{module}"), name)
