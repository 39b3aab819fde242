"""Offline RL data: ``GripSelect-v0`` episodes logged by a stated behaviour policy, written as a
Minari dataset (``grip-env export minari``; needs the ``offline`` extra).

Modules: ``behaviour`` (the seeded behaviour policies), ``reference`` (exact expected returns of
the random and the oracle pick: Minari's reference scores), ``minari_export`` (the episodes and
the metadata, written with Minari).
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

_LAZY = {
    "BehaviourPolicy": "behaviour",
    "ExportPlan": "minari_export",
    "export_minari": "minari_export",
    "reference_returns": "reference",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f"grip_env.offline.{_LAZY[name]}"), name)
