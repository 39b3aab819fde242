"""Simulation layer: the only package that calls a physics engine (pybullet, mujoco)."""

# world first: it imports pybullet with the native start-up banner silenced
from grip_env.sim.world import MM, Body, World  # isort: skip
from grip_env.label_model import LABEL_MODEL, label_model_of, label_model_warning
from grip_env.sim.engine import ENGINES, Engine, EngineUnavailable, make_world, require_engine
from grip_env.sim.execution import OUTCOME_COLUMNS, run_trial_outcomes, run_trials
from grip_env.sim.frames import render_trial_strip, trial_frames
from grip_env.sim.hand import HAND_URDF, Hand
from grip_env.sim.trial import TRIAL_PHASES, GripPlan, TrialResult, TrialScene, grip_plans
from grip_env.sim.uncertainty import TrialNoise, object_mass_kg, sample_noise, zero_noise

__all__ = [
    "ENGINES",
    "HAND_URDF",
    "LABEL_MODEL",
    "MM",
    "OUTCOME_COLUMNS",
    "TRIAL_PHASES",
    "Body",
    "Engine",
    "EngineUnavailable",
    "GripPlan",
    "Hand",
    "TrialNoise",
    "TrialResult",
    "TrialScene",
    "World",
    "grip_plans",
    "label_model_of",
    "label_model_warning",
    "make_world",
    "object_mass_kg",
    "render_trial_strip",
    "require_engine",
    "run_trial_outcomes",
    "run_trials",
    "sample_noise",
    "trial_frames",
    "zero_noise",
]
