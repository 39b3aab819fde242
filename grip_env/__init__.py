"""grip-env: learning which Barrett BH8-280 grips hold.

Importing the package registers the Gymnasium environments ``GripSelect-v0`` and ``GripAccept-v0``.
"""

from grip_env.params import GraspParams

__version__ = "0.1.0"
__all__ = ["GraspParams", "__version__"]

from grip_env.envs.registration import register_envs

register_envs()
