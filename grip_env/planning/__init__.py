"""Planning: from an object's contour to candidate grips and their twelve measures.

Grasp synthesis (:mod:`~grip_env.planning.grasps`), the Barrett BH8-280 planar kinematics and
configuration search (:mod:`~grip_env.planning.barrett`), the finger's closing posture
(:mod:`~grip_env.planning.finger`), the twelve quality measures
(:mod:`~grip_env.planning.features`), the ε metric (:mod:`~grip_env.planning.epsilon`) and the
candidate pipeline that chains them (:mod:`~grip_env.planning.pipeline`). Pure numpy: no
simulator, dataset or environment. ``grip_env.pipeline`` and ``grip_env.features`` are the
public paths of the last two (the design's contract).
"""
