"""Simulation layer: the only package that calls pybullet."""

from grip_env.sim.world import MM, Body, World

__all__ = ["MM", "Body", "World"]
