"""Registration of the grip environments with Gymnasium (done on ``import grip_env``)."""

from __future__ import annotations

import gymnasium

ENV_IDS: dict[str, str] = {
    "GripSelect-v0": "grip_env.envs.select:GripSelectEnv",
    "GripAccept-v0": "grip_env.envs.accept:GripAcceptEnv",
}


def register_envs() -> None:
    """Register ``GripSelect-v0`` and ``GripAccept-v0`` (idempotent).

    With no arguments, ``gymnasium.make`` gives the live PyBullet backend on the default object set;
    pass ``data=`` (a dataset path or DataFrame) to replay recorded outcomes instead.
    """
    for env_id, entry_point in ENV_IDS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(id=env_id, entry_point=entry_point)
