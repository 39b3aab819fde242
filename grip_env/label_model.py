"""The label model: the id of everything that decides a trial's outcome.

The scene, the hand and its controller, the noise and how it is drawn, the disturbance ramp and
the judgement together make a label. ``LABEL_MODEL`` names the one this code implements; every
dataset's manifest records it as ``label_model``, and ``tests/test_golden.py`` pins a fixed set
of trial outcomes to it. A change that moves any trial outcome is a new label model: bump the id,
renew the golden recording (``python -m tests.golden --record``) and regenerate the standard
dataset. It lives outside ``grip_env.sim`` (which re-exports it) so that reading a manifest
does not import PyBullet.

Each engine (``sim.engine``) has its own label model (``ENGINE_LABEL_MODELS``): the same grip,
draws and protocol in another contact model is another label. A manifest records the label model
beside the engine's name and version (``manifest["engine"]``); each engine's golden recording
(``tests/golden.py --engine NAME``) pins its id.

History of PyBullet's (the figures behind each are in BENCHMARKS.md):

- ``2026.12-crn``: every trial in a world built for it; trial k of every grip of an object
  shares one draw (common random numbers, keyed by the object's id); the palm's error in the
  palm frame; a quasi-static ramp (each level held until the object rests: at least 3 steps, at
  most 60). Before it, datasets recorded no label model.
- ``2026.12-xm``: the same on every x86-64-v3 machine (glibc's libm is not held: below v3 its
  non-FMA sin/cos move trials; BENCHMARKS.md, "Each engine's labels frozen"). The simulated
  shape's simplification decides with elementwise arithmetic (a BLAS product, rounded
  differently on another CPU, kept other vertices of a symmetric contour), and a mesh's posed
  vertices are rounded to 1e-6 mm before its outline is built. The simulated shapes of curved
  and mesh objects moved by their last bits (20 of the default study's 80), which moves some of
  their trials as any 1 nm change does.
- ``2026.12-hertz``: the pads' torsional arm 2 mm (3 before), the Hertzian (3 pi / 16) a at the
  squeeze on a held box, and a ramp that doubles from 2 g to 16 g and rises by 2^(1/4) from
  there (25 levels before, 16 now; the same above 16 g), 27 % fewer protocol steps a trial.
  The arm was decided on the contact's physics; the grid passed a convergence criterion
  written before it ran (success alike 99.3 %, Spearman 0.99). Shared with MuJoCo's
  ``mujoco-2026.12-hertz``. BENCHMARKS.md, "The next label model of both engines".
- ``2026.12-worm``: the worm gear's stop holds any load (``hand.HOLD_FACTOR`` infinite; it held
  5 times the motor's torque, a figure with no source). Barrett's single-start worms are
  self-locking, and MuJoCo's stop already had no bound: both engines now model the same gear.
  A stop of 50 times the motor gives the same outcomes as the unbounded one on 150 standard
  grips, bit for bit. BENCHMARKS.md, "The worm gear's stop, alike in both engines".
- ``2026.12-restore``: every climb of the ramp starts from the saved moment. Bullet's
  ``restoreState`` wrote the saved contact points into the manifolds as they were, beside the
  points of the moment, so each fingertip of a restored grip pressed through stacked points, a
  whole pad spring each (up to twice the hand's squeeze), and each direction's climb began from
  a state set by the climb before it. The world now empties every manifold after the bodies are
  restored and finds the contacts afresh (``World.restore``): every restore is the same, bit for
  bit, whatever ran before it. MuJoCo's restore was already exact; its label model is unchanged.
  BENCHMARKS.md, "A restore that keeps no contact of the moment".

MuJoCo's (``sim.engine: mujoco``):

- ``mujoco-draft``: the first port; its arm's drives, outside the contact solve, shook most
  grips loose at the lift.
- ``mujoco-2026.12-servo``: the arm's joints are servo constraints solved with the contacts
  (time constant ``SERVO_TIME_CONSTANT_S``, a reference moving at the step's speed), as Bullet
  solves its motors; everything else as the draft. Known defects, for the next: the worm-gear
  stops give up to 8 mrad (MuJoCo's constants are not renewed after the rotor inertia is added)
  and the pads are about five times the rubber's stiffness.
- ``mujoco-2026.12-pads``: both defects of ``mujoco-2026.12-servo`` fixed, together (fixing only
  the first doubled the squeeze at the close: a stop that holds locks in what a too-stiff pad
  rings to). (1) *Stale constants*: MuJoCo sizes every constraint's softness from inverse weights
  computed at compile time, and the world then added the fingers' rotor inertia (10-100 times the
  links') and the object's trial mass; the worm-gear stops were as soft as for the bare links,
  loaded joints sat up to 8.05 mrad below their floors (PyBullet 0.34). Now every mass or inertia
  change renews MuJoCo's constants (``mj_setConst``) and the pads' ``solref`` before the next step
  (the motors' gains stay sized as compiled: renewed with the rotor inertia they dropped grips at
  the lift through mujoco #3443). (2) *Pads five times too stiff*: force over depth was 106-122
  kN/m against the rubber's 22.6, because MuJoCo's impedance (0.9-0.95) mixes into a direct
  ``solref`` given per 80 g. Now a pad's ``solref`` is derived from MuJoCo's constraint model with
  the contact's own inverse weight and a constant impedance of 0.3 (``pad_solref``,
  ``PAD_IMPEDANCE``), so that force over depth is 22.6 kN/m and the damping 8.5 N s/m, the
  rubber's (measured, ``tests/test_mujoco_world.py``). With the softer friction regularisation
  this brings, the creep control NoSlip needs 5 iterations (2 let the held box creep out at 41 %
  of Coulomb). BENCHMARKS.md, "MuJoCo's pads and worm gear: label model mujoco-2026.12-pads".
- ``mujoco-2026.12-drives``: the hand's motors solved with the contacts, as Bullet solves its
  motors and the arm's servos are. Each motor was an actuator whose velocity gain ``implicitfast``
  applies after the contact solve (mujoco #3443), sized from the joints' inertias without their
  rotors (a stop-gap: sized with them, grips dropped at the lift), which also left joint 3's
  stall torque short of its cap (0.513 N m for 0.53-0.56). Each motor is now a fixed tendon from
  its joint to a reference joint turning at the motor's target speed, whose friction loss, the
  motor's torque, the solver bounds: it holds the joint to its speed within its torque and, stalled,
  presses exactly its torque. BENCHMARKS.md, "label model mujoco-2026.12-drives".
- ``mujoco-2026.12-lean``: the same hand in 4 physics substeps of the protocol step (5 before),
  chosen by a convergence criterion written before measuring (150 trials against 16 substeps with
  generous solver and NoSlip iterations). The worm gear's stop and the motors' rows keep the time
  constant every ``-drives`` label had, 1/600 s, now fixed in seconds (``STIFF_TIME_CONSTANT_S``;
  before, two physics steps of whatever count). Against ``-drives`` on the same 150 trials:
  success alike 98 %, Spearman 0.99. BENCHMARKS.md, "Cheaper MuJoCo physics per label".
- ``mujoco-2026.12-hertz``: the protocol change of PyBullet's ``2026.12-hertz`` (the 2 mm arm,
  the ramp doubling below 16 g; success alike 98.7 %, Spearman 0.99 for the grid alone), the
  same hand and integration as ``-lean``.
- ``mujoco-2026.12-together``: the ramp's directions climb together, one level each in turn, each
  resumed bit for bit where it paused (``MujocoWorld.resume``), so none climbs past the weakest
  level found. Every outcome is ``-hertz``'s bit for bit but the step count, 10-15 % fewer steps a
  trial (PyBullet cannot resume a climb exactly and keeps climbing them one after another).
  BENCHMARKS.md, "MuJoCo's directions climb together".
"""

from __future__ import annotations

LABEL_MODEL = "2026.12-restore"
#: MuJoCo's label model (``sim.engine: mujoco``), pinned by its own golden recording
#: (``python -m tests.golden --engine mujoco --record`` renews it; BENCHMARKS.md, "PyBullet
#: beside MuJoCo").
MUJOCO_LABEL_MODEL = "mujoco-2026.12-together"
#: Each engine's label model: PyBullet's is the standard dataset's.
ENGINE_LABEL_MODELS = {"pybullet": LABEL_MODEL, "mujoco": MUJOCO_LABEL_MODEL}
#: What a manifest written before label models were recorded is taken to hold.
UNRECORDED = "unrecorded"


def label_model_for(engine: str) -> str:
    """The label model this code implements in ``engine`` (``sim.engine``).

    Raises:
        ValueError: an unknown engine.
    """
    if engine not in ENGINE_LABEL_MODELS:
        raise ValueError(f"unknown engine {engine!r}: one of {', '.join(ENGINE_LABEL_MODELS)}")
    return ENGINE_LABEL_MODELS[engine]


def engine_of(manifest: dict) -> str:
    """The engine that made a dataset's labels: its manifest's ``engine`` record, else its
    config's ``sim.engine``, else PyBullet (every dataset made before engines could be chosen)."""
    recorded = manifest.get("engine")
    if isinstance(recorded, dict) and isinstance(recorded.get("name"), str):
        return recorded["name"]
    config = manifest.get("config")
    sim = config.get("sim") if isinstance(config, dict) else None
    engine = sim.get("engine") if isinstance(sim, dict) else None
    return engine if isinstance(engine, str) else "pybullet"


def expected_label_model(manifest: dict) -> str:
    """The label model this code makes in the engine a manifest names (PyBullet's when the
    engine is not one this code knows)."""
    return ENGINE_LABEL_MODELS.get(engine_of(manifest), LABEL_MODEL)


def label_model_of(manifest: dict) -> str:
    """The label model a dataset manifest records (``UNRECORDED`` for older datasets)."""
    value = manifest.get("label_model")
    return value if isinstance(value, str) and value else UNRECORDED


def label_model_warning(manifest: dict, where: str = "dataset") -> str | None:
    """One line saying that ``where``'s labels come from another label model than this code
    makes in its engine, or None."""
    found, expected = label_model_of(manifest), expected_label_model(manifest)
    if found == expected:
        return None
    return (f"{where} was labelled by label model {found!r}, this grip-env's is {expected!r}: "
            f"its outcomes are not what this code produces (regenerate it to compare)")
