"""grip-env: learning which Barrett BH8-280 grips hold.

Importing the package registers the Gymnasium environments ``GripSelect-v0`` and ``GripAccept-v0``,
and the mesh object sets with ``grip_env.objects.load_object_set``.
"""

from grip_env.portable_math import hold_at_v3

hold_at_v3()  # before numpy loads: the same labels on every x86-64 machine

from grip_env.params import GraspParams  # noqa: E402

__version__ = "0.1.0"
__all__ = ["GraspParams", "__version__"]

import grip_env.mesh_sets  # noqa: E402, F401  registers the mesh sets with load_object_set
from grip_env.envs.registration import register_envs  # noqa: E402

register_envs()
