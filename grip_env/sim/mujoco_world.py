"""``MujocoWorld``: the MuJoCo side of ``grip_env.sim.engine``. With ``mujoco_rendering`` (its
frames), the only modules that import mujoco.

It builds the scene ``World`` builds, from the same sources: the same table, the object as one
free body of the same convex pieces (prisms of its simulated shape; MuJoCo collides each as its
convex hull, with no margin to erode), and the same mounted URDF through MuJoCo's URDF compiler
(static links kept apart, as PyBullet keeps them). What the import lacks is added in code:

* **Ids as PyBullet gives them.** Bodies are numbered in the order they are added; a robot's link
  ``i`` is the child link of the URDF's ``i``-th joint (-1 its root), so ``Hand`` addresses both
  engines alike. Self-collision excludes every ancestor, as ``URDF_USE_SELF_COLLISION_EXCLUDE_ALL
  _PARENTS`` does.
* **Friction as Bullet combines it.** MuJoCo mixes two geoms' frictions by their maximum; Bullet
  multiplies lateral frictions and combines torsional ones as ``s0 mu1 + s1 mu0``. Every contact
  of a free body is therefore an explicit contact pair carrying Bullet's product (condim 4 where
  it has torsion), rewritten whenever a friction changes (``set_dynamics``, ``set_pad_friction``).
* **Motors as Bullet's, solved with the contacts.** A velocity motor drives a joint to its
  target speed within its torque; a position motor to ``gain (target - q) / dt`` (the speed
  computed once a protocol step, from where the joint is, as Bullet computes it once a step).
  Bullet solves each motor as a velocity constraint bounded by its torque, together with the
  contacts. MuJoCo's constraint of that form is friction loss: a velocity row bounded by a
  force. Each hand joint ``q`` is therefore tied by a fixed tendon ``q - q_ref`` to a reference
  joint of its own (a hinge of ``DRIVE_REFERENCE_INERTIA_KG_M2``, its speed set to the motor's
  target speed every protocol step); the tendon's friction loss is the motor's torque. The
  solver holds the joint to the target speed within that torque (``DRIVE_IMPEDANCE``; NoSlip,
  which also iterates friction-loss rows, tightens it), and a stalled motor presses exactly its
  torque (``drive_torques``).
  MuJoCo's actuators would not do: ``implicitfast`` applies a drive's velocity gain after the
  contact solve (mujoco #3443), so the contacts are solved for a hand lighter than it moves,
  and an explicit drive stable at the coupled finger joints' mass matrix is too weak to press its
  torque at a stall (BENCHMARKS.md, "label model mujoco-2026.12-drives").
* **The arm's joints as servo constraints** (the gantry's ``ARM_JOINTS``): MuJoCo adds a drive's
  implicit damping after the constraint solve (mujoco #3443), and the arm's drives, loaded by a
  grip, chattered at their 400 N limit every substep and shook the object loose. Each arm joint
  is instead held by a joint equality constraint solved with the contacts, as Bullet solves its
  motors: critically damped with ``SERVO_TIME_CONSTANT_S``, its reference moving at constant
  speed from the last target to the new one through each protocol step, led by twice the time
  constant times that speed (so a constant speed is tracked without lag). Its force is not
  capped; ``servo_peak_n`` and ``servos_within_limits`` record whether it ever needed more than
  the arm's limit (it does not in a trial, ``tests/test_mujoco_world.py``).
* **The worm gear's stop** is the joint's lower limit (``joint_floors``) with the time constant
  ``STIFF_TIME_CONSTANT_S``, fixed in seconds. MuJoCo limits have no force cap: the stop holds
  whatever load (Bullet's holds ``holds`` N·m).
* **Compliant pads.** A link made compliant (``set_contact_compliance``) contacts through a
  spring of the given stiffness and a damper of the given damping, in N/m and N s/m as PyBullet's
  pads (``pad_solref``): a constant impedance ``PAD_IMPEDANCE`` and a direct ``solref`` scaled
  by the contact's own inverse weight, so that force over depth is the stiffness whatever the
  bodies' masses (MuJoCo's constraint model, derived at ``pad_solref``).
* **Rotor inertia** (``add_axis_inertia``) is added to the link's inertia tensor about its own
  axis, as the PyBullet world does.
* **Constants renewed.** MuJoCo sizes every constraint's softness from inverse weights computed
  when the model is compiled (``body_invweight0``, ``dof_invweight0``). Every change of a mass
  or an inertia after compiling (the rotor inertia, the object's trial mass) renews them
  (``mj_setConst``) before the next step, and with them the pads' ``solref``.

Solver: Newton with elliptic friction cones, ``IMPRATIO`` and ``NOSLIP_ITERATIONS`` (the creep
controls; sources: ``/work/shared/notes/mujoco-grasping.md``), ``sim.solver_iterations`` at most.
"""

from __future__ import annotations

import functools
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from grip_env.objects import PlanarObject
from grip_env.objects.simulated import DEFAULT_TOLERANCE_MM
from grip_env.sim.body import MM, Body
from grip_env.sim.gantry import ARM_JOINTS, mounted_urdf
from grip_env.sim.mujoco_rendering import Renderer, look_at

#: Elliptic cones' ratio of frictional to normal impedance: 10 as in DexGraspBench and MuJoCo's
#: docs' advice against slow slip (mujoco #3328 measured creep 10-30x lower than at 1).
IMPRATIO = 10.0
#: NoSlip post-iterations, chosen by measurement (mujoco #3328: 10 cut creep about 110-fold): on
#: the held box with the rubber's pads, 2 let it creep out at 41 % of mu times its normal forces;
#: 5 and 10 hold it to within 0.01 % (BENCHMARKS.md, "label model mujoco-2026.12-pads").
NOSLIP_ITERATIONS = 5
#: A hand motor's constraint impedance (constant), with the time constant
#: ``STIFF_TIME_CONSTANT_S`` (about the stiffest the physics step allows): the share of a speed
#: error its friction-loss row removes in a step; the arm's servos' 0.95. Not a tuning knob: 0.9,
#: 0.95 and 0.99 give the same squeeze on the held box (79.9 N) and the same outcomes on 150
#: cross-check trials within one trial (BENCHMARKS.md, "label model mujoco-2026.12-drives").
DRIVE_IMPEDANCE = 0.95
#: The inertia (kg m^2) of a motor's reference joint: so heavy that the motor's torque (at most
#: a few N·m) changes its speed by under 1e-6 rad/s in a protocol step, and so light against the
#: fingers' joints (about 1e-3) that its share of the drive's inverse weight is below 1e-7.
DRIVE_REFERENCE_INERTIA_KG_M2 = 1e4
#: The largest phase (rad) a pad's spring may turn in one physics step: MuJoCo integrates a
#: contact's spring semi-implicitly, and the pad against its 80 g object (85 Hz) at the
#: protocol's 240 Hz turns 2.2 rad a step and diverges (measured: the object flew off at the first
#: touch). The world steps the physics in substeps short enough to resolve the pad: 4 at 240 Hz
#: (0.55 rad). Chosen by a convergence criterion written before measuring (150 trials against 16
#: substeps with NoSlip 20 and Newton 200 at 1e-10, the same stop in seconds; BENCHMARKS.md,
#: "Cheaper MuJoCo physics per label"): 4 substeps pass (success alike 98 %, Spearman 0.983,
#: mean -1.7 g [-2.9, -0.4] within 5 %); 3 (0.74 rad) diverge or drop grips.
PAD_PHASE_PER_STEP = 0.6
#: The mass whose natural frequency against a pad sets the substeps (``PAD_PHASE_PER_STEP``): the
#: 80 g object the pad's damping was derived for (``sim.pad_damping_n_s_per_m``).
PAD_REFERENCE_MASS_KG = 0.08
#: A pad contact's impedance, constant over its depth. MuJoCo's contact force is
#: ``f = (a_ref - a) / R`` with ``R = (1 - d) / d * A`` (``A`` the contact's inverse weight,
#: ``d`` the impedance), so besides its spring and damper it carries an inertia ``1 / R`` that
#: resists the contact's own acceleration: ``d / (1 - d)`` times the contact's effective mass,
#: which no rubber pad has. Measured on the held box (BENCHMARKS.md): force over depth is the
#: rubber's at every impedance from 0.1, and the outcome the same from 0.1 to 0.9 (held up to
#: 38.1 g); at 0.05 and below the object never comes to rest in the hand and slides out, at 0.9
#: (MuJoCo's default, an inertia 9 times the contact's) the close's impact locks in 11 % more
#: squeeze. 0.3, inside that plateau: an inertia of 0.43 times the contact's.
PAD_IMPEDANCE = 0.3
#: The arm's servo constraints' time constant (s, damping ratio 1). The idealised arm reaches its
#: targets within its force (``Hand.max_palm_force_n``, 400 N), so its servo is the stiffest whose
#: force never exceeds that limit in a trial: the approach asks the 3.3 kg the z axis carries for
#: a 0.3 m/s step in speed, about 2 N s, which a servo of time constant T answers with about
#: 2 N s / T (measured on 20 trials of the standard dataset: 1,097 N at 1.7 ms, 564 N at 3.3 ms,
#: 299 N at 6.7 ms, the last never over the limit; the outcomes alike at all three). MuJoCo solves
#: the servos with the contacts, as Bullet solves its motors; their references move at constant
#: speed through a step, and that speed is their velocity reference.
SERVO_TIME_CONSTANT_S = 1.0 / 150.0
#: The time constant (s, damping ratio 1) of the worm gear's stop and of the hand motors' rows.
#: Both stand for rigid parts (a worm gear that cannot be back-driven, a stiff current-limited
#: velocity loop), so they are as stiff as the physics allows; but a stiffness is a property of
#: the hand, not of the integration, so it is fixed in seconds: 1/600 s, the two physics steps of
#: 5 substeps at 240 Hz with which every ``mujoco-2026.12-drives`` label was made. Before, it was
#: two physics steps of whatever substep count, so each count was another stop. At 4 substeps it
#: is 1.6 physics steps, below MuJoCo's ``refsafe`` (which is turned off for it): measured stable
#: and faithful there (the stop's slip 0.46 mrad, as at 5 substeps); at 3 substeps (1.2 steps)
#: the simulation diverges (BENCHMARKS.md, "Cheaper MuJoCo physics per label").
STIFF_TIME_CONSTANT_S = 1.0 / 600.0
#: Multi-point contact between two convex geoms (MuJoCo's ``multiccd``; on by default since
#: MuJoCo 3.3, where the flag became ``mjDSBL_MULTICCD``): a face pressed flat on a face gets up to
#: four contact points around their overlap, as Bullet's manifold does, instead of one. Kept on,
#: MuJoCo 4.0.1's default, and named so that a change of MuJoCo's default cannot move the labels.
#: The fingers touch mostly through their 3 mm tip spheres (one point either way); what it
#: carries is the object's seat on the table: with one point a pair the analytic blocks find no
#: slip threshold and the mesh family's retest falls from 0.70 to 0.60 (BENCHMARKS.md, "Mesh
#: objects in the cross-check").
MULTI_CONTACT = True
#: Bullet's default position gain of a position motor when none is given.
DEFAULT_POSITION_GAIN = 0.1
GRAVITY = (0.0, 0.0, -9.81)
#: What ``pause`` keeps of ``mjData``: everything a step reads and does not derive.
INTEGRATION_STATE = mujoco.mjtState.mjSTATE_INTEGRATION


@dataclass(frozen=True)
class _Commands:
    """What the controllers commanded at a saved moment (``MujocoWorld.save``)."""

    servo_from: NDArray[np.float64]
    servo_target: NDArray[np.float64]
    servo_limit: NDArray[np.float64]
    drive_command: NDArray[np.float64]
    drive_is_position: NDArray[np.bool_]
    drive_gain: NDArray[np.float64]
    drive_torques: NDArray[np.float64]
    joint_ranges: NDArray[np.float64]


@dataclass(frozen=True)
class _Saved:
    """A saved moment: the whole ``mjData`` (``save``) or its integration state (``pause``)."""

    data: mujoco.MjData | None
    state: NDArray[np.float64] | None
    commands: _Commands


class MujocoWorld:
    """A headless MuJoCo world; use as a context manager or ``close()``.

    Bodies are added first (``add_table``, ``add_object``, ``load_robot``); the model is compiled
    at the first call that needs it, after which no body can be added. With ``watch_servos`` the
    world records the arm servos' largest forces in every physics substep (``servo_peak_n``);
    off by default, as it costs about a tenth of a trial.
    """

    watch_servos: bool = False
    #: ``resume`` brings back the whole state and every command, so it continues bit for bit.
    resumes_exactly = True

    def __init__(self, timestep: float = 1.0 / 240.0, solver_iterations: int = 50) -> None:
        self.timestep = timestep
        self.solver_iterations = solver_iterations
        self._spec = mujoco.MjSpec()
        self._spec.option.timestep = timestep
        self._spec.option.gravity = GRAVITY
        self._spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        self._spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
        self._spec.option.impratio = IMPRATIO
        self._spec.option.noslip_iterations = NOSLIP_ITERATIONS
        self._spec.option.iterations = solver_iterations
        if not MULTI_CONTACT:
            self._spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_MULTICCD
        self._bodies: list[list[str]] = []  # per uid: body name of link -1, 0, 1, ...
        self._joints: list[list[str | None]] = []  # per uid: joint of link 0, 1, ... (None: fixed)
        self._free: list[bool] = []
        self.substeps = 1
        self._model: mujoco.MjModel | None = None
        self._saved: dict[int, _Saved] = {}  # by state id: save's and pause's
        self._spare: mujoco.MjData | None = None  # scratch for constants or a saved state
        self._addresses: dict[tuple[int, tuple[int, ...]], tuple[NDArray, NDArray]] = {}
        self._joint_rows: dict[tuple[int, tuple[int, ...]], NDArray[np.int64]] = {}
        # joint_floors' calls whose stops carry the stops' current time constant (rewritten
        # when it changes: pads added after the first call raise the substeps)
        self._floor_solref_set: set[tuple[int, tuple[int, ...]]] = set()
        self._floor_solref_value = 0.0  # the stops' time constant last written
        self._quat = np.empty(4)  # scratch for per-step orientation reads
        self._stale = False
        self._loaded = False  # a push or twist is applied (``xfrc_applied``)
        self._constants_stale = False
        self._pads: dict[int, tuple[float, float]] = {}  # geom: stiffness N/m, damping N s/m
        self._servo_names: list[str] = []  # the arm's joints, held by servo constraints
        self._drive_names: list[str] = []  # the hand's joints, driven by motors (``_add_drives``)
        self.servo_peak_n = np.zeros(0)  # the largest |force| each servo exerted so far
        self._renderers: dict[tuple[int, int], Renderer] = {}  # by (width, height)

    # ------------------------------------------------------------------ lifecycle
    def close(self) -> None:
        """Release the model, its data and its renderers (idempotent)."""
        self._close_renderers()
        self._model = None
        self._spare = None
        self._saved.clear()

    def __enter__(self) -> MujocoWorld:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def step(self, steps: int = 1) -> None:
        """Advance the simulation ``steps`` fixed steps; pushes and twists last one step.

        The arm's servos track a reference that moves at constant speed from the last target to
        the new one through the step, with that speed as their velocity reference."""
        m, d = self._ready()
        for _ in range(steps):
            self._set_drive_speeds(m, d)
            if self._arm_at_rest():
                self._step_still(m, d)
            else:
                self._step_moving(m, d)
            self._unload(d)
        self._stale = True

    def _arm_at_rest(self) -> bool:
        """Whether the servos' targets are, bit for bit, where they start the step (and no
        servo is watched, which needs every substep's forces)."""
        return not self.watch_servos and (
            self._servo_target.tobytes() == self._servo_from.tobytes())

    def _step_moving(self, m: mujoco.MjModel, d: mujoco.MjData) -> None:
        """One step of an arm on its way: each substep's references, then its physics."""
        offsets, held = self._substep_offsets, self._servo_references  # held: rows of eq_data
        start, speed = self._servo_from, (self._servo_target - self._servo_from) / self.timestep
        lead = 2.0 * self._servo_time_constant * speed
        references = np.multiply(offsets, speed)  # the bits of start + offsets * speed + lead
        references += start  # (its sums in its order)
        references += lead
        for reference in references:
            held[:] = reference
            mujoco.mj_step(m, d)
            if self.watch_servos:
                peak = self.servo_peak_n
                np.maximum(peak, np.abs(d.efc_force[self._servo_rows]), out=peak)
        self._servo_from = self._servo_target.copy()

    def _step_still(self, m: mujoco.MjModel, d: mujoco.MjData) -> None:
        """One step of an arm at rest: every substep's reference is then
        ``start + offset * 0.0 + 0.0``, the same bits as ``start + 0.0``, so the substeps run
        in one call to MuJoCo, bit for bit the moving arm's loop."""
        self._servo_references[:] = self._servo_from + 0.0
        mujoco.mj_step(m, d, self.substeps)

    def _unload(self, d: mujoco.MjData) -> None:
        """End a push or twist: each lasts one step."""
        if self._loaded:
            d.xfrc_applied[:] = 0.0
            self._loaded = False

    def servos_within_limits(self) -> bool:
        """Whether no arm servo ever exerted more than its force limit (the last commanded), as
        far as ``watch_servos`` watched."""
        return bool((self.servo_peak_n <= self._servo_limit).all())

    # ------------------------------------------------------------------ bodies
    def add_table(self, friction: float = 0.5, half_size_mm: float = 500.0) -> Body:
        """A static table whose top face is at z = 0."""
        name = self._new_body([f"table{len(self._bodies)}"], [], free=False)
        body = self._spec.worldbody.add_body(name=name, pos=[0, 0, -0.01])
        self._geom(body, type=mujoco.mjtGeom.mjGEOM_BOX,
                   size=[half_size_mm * MM, half_size_mm * MM, 0.01], friction=friction,
                   rgba=[1.0, 1.0, 1.0, 1.0])  # white, as PyBullet's (its look only)
        return Body(len(self._bodies) - 1, 0.0)

    def add_object(
        self, obj: PlanarObject, thickness_mm: float = 30.0, mass_kg: float = 0.3,
        friction: float = 0.5, rgba: tuple[float, float, float, float] = (0.15, 0.15, 0.15, 1.0),
        tolerance_mm: float = DEFAULT_TOLERANCE_MM,
    ) -> Body:
        """The object extruded to ``thickness_mm`` on z = 0, one convex prism per piece of its
        simulated shape, as a free body (``World.add_object``).

        Raises:
            ValueError: bad thickness or mass, or a shape that cannot be simulated whole.
        """
        from grip_env.sim.world import prism_inertia

        if thickness_mm <= 0 or mass_kg <= 0:
            raise ValueError(f"thickness and mass must be positive, got {thickness_mm}, {mass_kg}")
        shape = obj.simulated_shape(tolerance_mm)
        uid = len(self._bodies)
        name = self._new_body([f"object{uid}"], [], free=True)
        inertia, axes = prism_inertia(obj, thickness_mm)
        body = self._spec.worldbody.add_body(name=name)
        body.add_freejoint()
        body.explicitinertial = True
        body.mass = mass_kg
        body.ipos = [obj.centroid[0] * MM, obj.centroid[1] * MM, thickness_mm * MM / 2]
        body.iquat = [axes[3], axes[0], axes[1], axes[2]]
        body.inertia = [i * mass_kg for i in inertia]
        for k, piece in enumerate(shape.pieces):
            mesh = self._spec.add_mesh(name=f"{name}_piece{k}")
            mesh.uservert = np.asarray(_prism(piece, thickness_mm)).ravel().tolist()
            self._geom(body, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh.name,
                       friction=friction, rgba=rgba)
        return Body(uid, thickness_mm, (-1,), inertia)

    def add_mesh(
        self, path: str | Path, scale: float, com_mm: NDArray[np.float64],
        position_mm: NDArray[np.float64], orientation: tuple[float, float, float, float],
        mass_kg: float, friction: float, inertia_per_kg: tuple[float, float, float],
        axes: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0),
        rgba: tuple[float, float, float, float] = (0.15, 0.15, 0.15, 1.0),
    ) -> Body:
        """A mesh file as one free body of the pieces PyBullet builds from it: one convex hull
        per object (``o``/``g``) of the OBJ file (``read_obj_pieces``), scaled by ``scale`` (mm
        per mesh unit), its centre of mass ``com_mm`` (mesh frame) at ``position_mm``, the mesh
        frame turned by ``orientation`` (x, y, z, w), principal inertia per kg about ``axes``
        (``World.add_mesh``). The hulls are the mesh's own: Bullet grows each by its 1 mm
        collision margin, so PyBullet's body is 1 mm larger all round. ``top_mm`` is the top of
        the posed pieces (PyBullet's: of its turned bounding box, higher; no trial reads it).

        Raises:
            ValueError: bad scale or mass, or an unreadable mesh.
        """
        from grip_env.objects.meshes import read_obj_pieces

        if mass_kg <= 0 or scale <= 0:
            raise ValueError(f"mesh scale and mass must be positive, got {scale}, {mass_kg}")
        pieces = [piece * scale * MM for piece in read_obj_pieces(Path(path))]
        uid = len(self._bodies)
        name = self._new_body([f"object{uid}"], [], free=True)
        turn = np.empty(9)
        mujoco.mju_quat2Mat(turn, [orientation[3], *orientation[:3]])
        turn = turn.reshape(3, 3)
        origin = np.asarray(position_mm, float) - turn @ np.asarray(com_mm, float)
        body = self._spec.worldbody.add_body(name=name, pos=(origin * MM).tolist(),
                                             quat=[orientation[3], *orientation[:3]])
        body.add_freejoint()
        body.explicitinertial = True
        body.mass = mass_kg
        body.ipos = (np.asarray(com_mm, float) * MM).tolist()
        body.iquat = [axes[3], axes[0], axes[1], axes[2]]
        body.inertia = [i * mass_kg for i in inertia_per_kg]
        for k, piece in enumerate(pieces):
            mesh = self._spec.add_mesh(name=f"{name}_piece{k}")
            mesh.uservert = piece.ravel().tolist()
            self._geom(body, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh.name,
                       friction=friction, rgba=rgba)
        top = max(float((origin + (turn @ (piece.T / MM)).T)[:, 2].max()) for piece in pieces)
        return Body(uid, top, (-1,), tuple(map(float, inertia_per_kg)))  # type: ignore[arg-type]

    def add_sphere(
        self, radius_mm: float, mass_kg: float, friction: float, position_mm: NDArray[np.float64],
        inertia_kg_m2: float | None = None,
        rgba: tuple[float, float, float, float] = (0.15, 0.15, 0.15, 1.0),
    ) -> Body:
        """A free sphere centred at ``position_mm`` (``World.add_sphere``); its contacts are
        pairs, as every free body's.

        Raises:
            ValueError: a radius, mass or inertia that is not positive.
        """
        from grip_env.sim.world import sphere_inertia_per_kg

        inertia = sphere_inertia_per_kg(radius_mm, mass_kg, inertia_kg_m2)
        uid = len(self._bodies)
        name = self._new_body([f"object{uid}"], [], free=True)
        body = self._spec.worldbody.add_body(name=name,
                                             pos=(np.asarray(position_mm, float) * MM).tolist())
        body.add_freejoint()
        body.explicitinertial = True
        body.mass = mass_kg
        body.ipos = [0.0, 0.0, 0.0]  # MjSpec's default (NaN) compiles to the body's position
        body.inertia = [i * mass_kg for i in inertia]
        self._geom(body, type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[radius_mm * MM, 0.0, 0.0],
                   friction=friction, rgba=rgba)
        return Body(uid, float(position_mm[2]) + radius_mm, (-1,), inertia)

    def set_dynamics(self, body: Body, mass_kg: float, friction: float,
                     spinning_friction: float = 0.0) -> None:
        """Mass (with the whole body's inertia) and friction on every piece of ``body``
        (``World.set_dynamics``; pairs take Bullet's combination)."""
        m, _ = self._compiled()
        base = self._body_id(body.uid, -1)
        m.body_mass[base] = mass_kg
        m.body_inertia[base] = [i * mass_kg for i in body.inertia_per_kg]
        self._constants_stale = True
        for link in body.links:
            self._set_friction(body.uid, link, friction, spinning_friction)

    def pose_mm(self, body: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Position (mm) and quaternion (x, y, z, w) of a body's centre of mass frame."""
        position, orientation = self.pose_floats_mm(body)
        return np.asarray(position), np.asarray(orientation)

    def pose_floats_mm(
        self, body: int
    ) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
        """``pose_mm`` as plain float tuples (a per-step call)."""
        self._current()
        index = self._body_ids[body][0]
        x, y, z = self._xipos[index].tolist()
        mujoco.mju_mat2Quat(self._quat, self._ximat[index])
        w, qx, qy, qz = self._quat.tolist()
        return (x / MM, y / MM, z / MM), (qx, qy, qz, w)

    # ------------------------------------------------------------------ robots
    def load_robot(self, urdf: str | Path) -> int:
        """A URDF mounted on the gantry arm, fixed to the world, with its own inertia and
        self-collision between links that are not ancestors (``World.load_robot``)."""
        path = mounted_urdf(urdf)
        robot = mujoco.MjSpec.from_file(str(path))
        robot.compiler.fusestatic = False
        uid = len(self._bodies)
        prefix = f"robot{uid}/"
        joints, parents = _urdf_joints(path)
        root = _urdf_root_link(path)
        links = [root] + [child for _, _, child in joints]
        self._new_body([prefix + name for name in links],
                       [None if kind == "fixed" else prefix + name for name, kind, _ in joints],
                       free=False)
        frame = self._spec.worldbody.add_frame()
        frame.attach_body(robot.body(root), prefix, "")
        for child, parent in parents.items():  # every ancestor, not only the parent
            ancestor = parent
            while ancestor is not None:
                self._spec.add_exclude(bodyname1=prefix + ancestor, bodyname2=prefix + child)
                ancestor = parents.get(ancestor)
        for name, kind, _ in joints:
            if name in ARM_JOINTS:
                self._servo_names.append(prefix + name)
                self._spec.add_equality(type=mujoco.mjtEq.mjEQ_JOINT, name1=prefix + name)
            elif kind != "fixed":
                self._drive_names.append(prefix + name)
        return uid

    def link_count(self, body: int) -> int:
        """Number of links (= joints) of ``body``, the base not counted."""
        return len(self._joints[body])

    def link_pose_floats_mm(
        self, body: int, link: int
    ) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
        """Position (mm) and quaternion of a link's frame (its URDF frame), as plain floats."""
        self._current()
        index = self._body_ids[body][link + 1]
        x, y, z = self._xpos[index].tolist()
        w, qx, qy, qz = self._xquat[index].tolist()
        return (x / MM, y / MM, z / MM), (qx, qy, qz, w)

    def add_axis_inertia(self, body: int, link: int, axis: int, inertia_kg_m2: float) -> None:
        """Add ``inertia_kg_m2`` to a link's inertia about its local ``axis`` (0, 1, 2)."""
        m, _ = self._compiled()
        index = self._body_id(body, link)
        m.body_inertia[index], m.body_iquat[index] = _with_axis_inertia(
            m.body_inertia[index].tobytes(), m.body_iquat[index].tobytes(), axis,
            float(inertia_kg_m2))
        self._constants_stale = True

    def set_pad_friction(self, body: int, link: int, lateral: float, torsion_mm: float) -> None:
        """Friction of one link: lateral coefficient and torsional arm (mm)."""
        self._set_friction(body, link, lateral, torsion_mm * MM)

    def set_contact_compliance(self, body: int, link: int, stiffness_n_per_m: float,
                               damping_n_s_per_m: float) -> None:
        """Make one link's contacts a spring of ``stiffness_n_per_m`` and a damper of
        ``damping_n_s_per_m`` (``pad_solref``), and step the physics in substeps that resolve
        the spring against ``PAD_REFERENCE_MASS_KG`` (``PAD_PHASE_PER_STEP``)."""
        m, _ = self._compiled()
        omega = math.sqrt(stiffness_n_per_m / PAD_REFERENCE_MASS_KG)
        self.substeps = max(self.substeps, math.ceil(omega * self.timestep / PAD_PHASE_PER_STEP))
        m.opt.timestep = self.timestep / self.substeps
        self._set_servo_stiffness(m)
        for geom in self._link_geoms(body, link).tolist():
            self._pads[geom] = (float(stiffness_n_per_m), float(damping_n_s_per_m))
        self._constants_stale = True

    def set_joint(self, body: int, joint: int, position: float) -> None:
        """Teleport one joint (rad or m), at rest."""
        m, d = self._compiled()
        index = self._joint_id(body, joint)
        d.qpos[m.jnt_qposadr[index]] = float(position)
        d.qvel[m.jnt_dofadr[index]] = 0.0
        if index in self._servo_of:  # the arm's servo starts from where it was put
            self._servo_from[self._servo_of[index]] = float(position)
            self._servo_target[self._servo_of[index]] = float(position)
        self._stale = True

    def velocity_motors(self, body: int, joints: list[int], speeds: list[float],
                        torques: list[float]) -> None:
        """Velocity-controlled joint motors of limited torque (N·m)."""
        self._compiled()
        drives = self._drives(body, joints)
        self._drive_is_position[drives] = False
        self._drive_command[drives] = speeds
        self._set_drive_torques(drives, torques)

    def position_motors(self, body: int, joints: list[int], targets: list[float],
                        torques: list[float], gain: float | None = None) -> None:
        """Position-controlled joint motors of limited torque (N·m): each drives its joint at
        ``gain (target - q) / dt`` (Bullet's default gain if None)."""
        self._compiled()
        position_gain = DEFAULT_POSITION_GAIN if gain is None else gain
        hand = []
        for k, (joint, target, torque) in enumerate(zip(joints, targets, torques, strict=True)):
            servo = self._servo_of.get(self._joint_id(body, joint))
            if servo is not None:  # the arm: a constraint solved with the contacts
                self._servo_target[servo] = target
                self._servo_limit[servo] = torque
            else:
                hand.append(k)
        if not hand:
            return
        drives = self._drives(body, [joints[k] for k in hand])
        self._drive_is_position[drives] = True
        self._drive_gain[drives] = position_gain
        self._drive_command[drives] = [targets[k] for k in hand]
        self._set_drive_torques(drives, [torques[k] for k in hand])

    def joint_floors(self, body: int, joints: list[int], lowers: list[float],
                     uppers: list[float], holds: list[float]) -> None:
        """Set joints' lower and upper limits (stops; MuJoCo's hold any load, ``holds`` aside)."""
        m, _ = self._compiled()
        key = (body, tuple(joints))
        if key not in self._joint_rows:  # a per-step call: ids cached
            self._joint_rows[key] = np.array([self._joint_id(body, j) for j in joints], int)
        rows = self._joint_rows[key]
        self._jnt_range[rows, 0] = lowers
        self._jnt_range[rows, 1] = uppers
        stiff = self._stiff_time_constant(m)
        if stiff != self._floor_solref_value:
            self._floor_solref_set.clear()
            self._floor_solref_value = stiff
        if key not in self._floor_solref_set:  # the same value at every call while it holds
            self._jnt_solref[rows] = (stiff, 1.0)
            self._floor_solref_set.add(key)

    def joint_limits(self, body: int, joint: int) -> tuple[float, float]:
        """A joint's lower and upper limits (rad) as loaded (the URDF's)."""
        self._compiled()
        low, high = self._loaded_ranges[self._joint_id(body, joint)]
        return float(low), float(high)

    def joint_states(
        self, body: int, joints: list[int]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Positions, velocities and applied motor torques of ``joints`` (an arm joint's: its
        servo constraint's force in the last physics step)."""
        m, d = self._compiled()
        ids = [self._joint_id(body, j) for j in joints]
        drive_torques = self.drive_torques()
        forces = [float(d.efc_force[self._servo_of[i]]) if i in self._servo_of
                  else float(drive_torques[self._drive_of[i]]) for i in ids]
        return (d.qpos[m.jnt_qposadr[ids]].copy(), d.qvel[m.jnt_dofadr[ids]].copy(),
                np.array(forces))

    def joint_positions_velocities(self, body: int,
                                   joints: list[int]) -> tuple[list[float], list[float]]:
        """Positions and velocities of ``joints``, as lists (addresses cached: a per-step call)."""
        positions, velocities = self._joint_addresses(body, joints)
        return self._qpos[positions].tolist(), self._qvel[velocities].tolist()

    def joint_positions(self, body: int, joints: list[int]) -> list[float]:
        """Positions of ``joints``, as a list (a per-step call)."""
        return self._qpos[self._joint_addresses(body, joints)[0]].tolist()

    def _joint_addresses(self, body: int,
                         joints: list[int]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """The ``qpos`` and ``qvel`` addresses of ``joints`` (cached, as ``intp``: numpy gathers
        with those about three times faster than with MuJoCo's ``int32``)."""
        key = (body, tuple(joints))
        if key not in self._addresses:
            m, _ = self._compiled()
            ids = [self._joint_id(body, j) for j in joints]
            self._addresses[key] = (m.jnt_qposadr[ids].astype(np.intp),
                                    m.jnt_dofadr[ids].astype(np.intp))
        return self._addresses[key]

    def touching_links(self, body: int, other: int) -> set[int]:
        """The links of ``body`` in contact with ``other`` (in the last step)."""
        m, d = self._compiled()
        if not d.ncon:
            return set()
        bodies = m.geom_bodyid[d.contact.geom[: d.ncon]]  # (ncon, 2)
        uids = self._body_uid[bodies]
        first = (uids[:, 0] == body) & (uids[:, 1] == other)
        second = (uids[:, 1] == body) & (uids[:, 0] == other)
        links = np.concatenate([self._body_link[bodies[first, 0]],
                                self._body_link[bodies[second, 1]]])
        return set(links.tolist())

    def contact_normal_force_n(self, body: int, other: int) -> float:
        """The sum of the normal forces (N) of ``body``'s contacts with ``other`` in the last
        step."""
        m, d = self._compiled()
        uids, total, wrench = self._body_uid, 0.0, np.empty(6)
        for i, contact in enumerate(d.contact[: d.ncon]):
            pair = {uids[m.geom_bodyid[contact.geom1]], uids[m.geom_bodyid[contact.geom2]]}
            if pair == {body, other}:
                mujoco.mj_contactForce(m, d, i, wrench)
                total += wrench[0]
        return float(total)

    # ------------------------------------------------------------------ states and loads
    def save(self) -> int:
        """Save the whole simulation state and the commands in memory; returns a state id."""
        m, d = self._compiled()
        data = self._spare_data()
        mujoco.mj_copyData(data, m, d)
        return self._keep(data, None)

    def pause(self) -> int:
        """Save a moment to ``restore`` or ``resume`` before the next step reads anything
        else: what the steps start from (MuJoCo's integration state: positions, velocities, the
        solver's warm start, applied loads, time) and every command, without the rest of
        ``mjData`` that ``save`` copies (contacts, forces: the next step derives them again);
        returns a state id. The steps after it are bit for bit ``save``'s, and it allocates no
        ``mjData``."""
        m, d = self._compiled()
        state = np.empty(mujoco.mj_stateSize(m, INTEGRATION_STATE))
        mujoco.mj_getState(m, d, state, INTEGRATION_STATE)
        return self._keep(None, state)

    def _keep(self, data: mujoco.MjData | None, state: NDArray[np.float64] | None) -> int:
        key = max(self._saved, default=-1) + 1
        m = self._model
        self._saved[key] = _Saved(data, state, _Commands(
            self._servo_from.copy(), self._servo_target.copy(), self._servo_limit.copy(),
            self._drive_command.copy(), self._drive_is_position.copy(), self._drive_gain.copy(),
            m.tendon_frictionloss.copy(), self._jnt_range.copy()))
        return key

    def restore(self, state: int) -> None:
        """Return the world to a saved state. Of the commands, only the servos' start and the
        motors' targets come back: the limits and the motors' torques and modes stay, for the
        caller to command again (the trial's hand does, ``Hand.restore``)."""
        m, d = self._compiled()
        saved = self._saved[state]
        if saved.data is not None:
            mujoco.mj_copyData(d, m, saved.data)
        else:  # a pause: what the next step reads is set, the rest is derived again by it
            mujoco.mj_setState(m, d, saved.state, INTEGRATION_STATE)
        self._servo_from = saved.commands.servo_from.copy()
        self._drive_command = saved.commands.drive_command.copy()
        self._stale = True

    def resume(self, state: int) -> None:
        """Return the world to a saved or paused state with every command as it was then: the
        world goes on bit for bit as it would have from that moment (``resumes_exactly``)."""
        m, _ = self._compiled()
        self.restore(state)
        saved = self._saved[state].commands
        self._servo_target = saved.servo_target.copy()
        self._servo_limit = saved.servo_limit.copy()
        self._drive_is_position = saved.drive_is_position.copy()
        self._drive_gain = saved.drive_gain.copy()
        m.tendon_frictionloss[:] = saved.drive_torques
        self._jnt_range[:] = saved.joint_ranges

    def forget(self, state: int) -> None:
        """Free a saved state (a saved ``mjData`` is kept as the spare, ``_spare_data``)."""
        saved = self._saved.pop(state, None)
        if saved is not None and saved.data is not None:
            self._spare = saved.data

    def push(self, body: int, force_n: NDArray) -> None:
        """A world-frame force (N) through ``body``'s centre of mass, for the next step."""
        self._compiled()
        self._xfrc_applied[self._body_ids[body][0], :3] = force_n
        self._loaded = True

    def twist(self, body: int, torque_nm: NDArray) -> None:
        """A world-frame torque (N·m) on ``body``, for the next step."""
        self._compiled()
        self._xfrc_applied[self._body_ids[body][0], 3:] = torque_nm
        self._loaded = True

    def set_gravity(self, gravity: tuple[float, float, float]) -> None:
        """Gravity (m/s², world frame)."""
        m, _ = self._compiled()
        m.opt.gravity[:] = gravity

    def set_colour(self, body: Body, rgba: tuple[float, float, float, float]) -> None:
        """Paint every geom of ``body`` in ``rgba`` (its look only)."""
        m, _ = self._compiled()
        for link in body.links:
            m.geom_rgba[self._link_geoms(body.uid, link)] = rgba

    def render(self, eye_mm: NDArray[np.float64], target_mm: NDArray[np.float64],
               width: int = 320, height: int = 240, fov_deg: float = 50.0) -> NDArray[np.uint8]:
        """RGB image (height, width, 3) seen from ``eye_mm`` towards ``target_mm`` (z up, vertical
        field of view ``fov_deg``), drawn by MuJoCo's own OpenGL renderer from the current state.

        It draws the geometry MuJoCo simulates (its URDF import keeps no visual meshes: the hand
        is its collision pieces), lit by MuJoCo's headlight. Headless, through EGL
        (``mujoco_rendering``); without a GPU, Mesa's software rasteriser draws it. Each frame size
        keeps its OpenGL context until ``close``.

        Raises:
            ValueError: a size below one pixel, the eye on the target, or no OpenGL here (the
                message says what to install).
        """
        if width < 1 or height < 1:
            raise ValueError(f"image size must be positive, got {width} x {height}")
        camera = look_at(np.asarray(eye_mm, float) * MM, np.asarray(target_mm, float) * MM)
        m, d = self._current()
        if (width, height) not in self._renderers:
            self._renderers[width, height] = Renderer(m, width, height)
        m.vis.global_.fovy = fov_deg
        return self._renderers[width, height].frame(m, d, camera)

    # ------------------------------------------------------------------ internals
    def _close_renderers(self) -> None:
        for renderer in self._renderers.values():
            renderer.close()
        self._renderers.clear()

    def _new_body(self, bodies: list[str], joints: list[str | None], free: bool) -> str:
        if self._model is not None:
            raise ValueError("bodies must be added before the world is first simulated")
        self._bodies.append(bodies)
        self._joints.append(joints)
        self._free.append(free)
        return bodies[0]

    def _geom(self, body: mujoco.MjsBody, friction: float, **attributes: object) -> None:
        geom = body.add_geom(**attributes)
        geom.friction = [friction, 0.0, 0.0]

    def _compiled(self) -> tuple[mujoco.MjModel, mujoco.MjData]:
        if self._model is None:
            self._compile()
        return self._model, self._data  # type: ignore[return-value]

    def _ready(self) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """Model and data with the constants renewed after any mass or inertia change."""
        m, d = self._compiled()
        if self._constants_stale:
            self._renew_constants(m)
        return m, d

    def _renew_constants(self, m: mujoco.MjModel) -> None:
        """Renew what MuJoCo derives from masses and inertias (``mj_setConst``, on scratch data
        at the model's reference pose, so the world's state is untouched) and the pads'
        ``solref``."""
        scratch = self._spare_data()
        mujoco.mj_resetData(m, scratch)  # as a new MjData: the reference pose
        mujoco.mj_setConst(m, scratch)
        self._spare = scratch
        self._update_pads(m)
        self._constants_stale = False

    def _update_pads(self, m: mujoco.MjModel) -> None:
        """Each compliant geom's contacts: pairs from both bodies' inverse weights (a pair of two
        compliant geoms: their springs in series); other contacts (with static bodies) from the
        geom's own, its impedance winning the mix."""
        if not self._pads:
            return
        invweight = m.body_invweight0[:, 0]
        for geom, (stiffness, damping) in self._pads.items():
            body = m.geom_bodyid[geom]
            m.geom_solref[geom] = pad_solref(stiffness, damping, invweight[body])
            m.geom_solimp[geom, :2] = PAD_IMPEDANCE
            m.geom_solmix[geom] = 1.0 / mujoco.mjMINVAL
        for k, (a, b) in enumerate(self._pair_geoms.tolist()):
            springs = [self._pads[g] for g in (a, b) if g in self._pads]
            if not springs:
                continue
            stiffness = 1.0 / sum(1.0 / s for s, _ in springs)
            damping = 1.0 / sum(1.0 / c for _, c in springs) if all(c for _, c in springs) else 0.0
            weight = invweight[m.geom_bodyid[a]] + invweight[m.geom_bodyid[b]]
            m.pair_solref[k] = pad_solref(stiffness, damping, weight)
            m.pair_solimp[k, :2] = PAD_IMPEDANCE

    def _spare_data(self) -> mujoco.MjData:
        """An ``MjData`` of the model free for any use (the spare, now taken, or a new one):
        scratch for the constants, or a saved state. Reusing one spares allocating its arena
        (about 16 MB, 0.9 ms)."""
        data, self._spare = self._spare, None
        return data if data is not None else mujoco.MjData(self._model)

    def _current(self) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """Model and data with positions computed from the current joint values."""
        m, d = self._compiled()
        if self._stale:
            mujoco.mj_kinematics(m, d)
            self._stale = False
        return m, d

    def _compile(self) -> None:
        spec = self._spec
        for k, geom in enumerate(spec.geoms):
            geom.name = geom.name or f"geom{k}"
        body_of = {geom.name: geom.parent.name for geom in spec.geoms}
        free = [g.name for uid, is_free in enumerate(self._free) if is_free
                for body in self._bodies[uid] for g in spec.body(body).geoms]
        for name in free:  # contacts of free bodies come from pairs only
            spec.geom(name).contype, spec.geom(name).conaffinity = 0, 0
        rank = {name: k for k, name in enumerate(free)}
        pairs = [(name, other) for name in free for other in body_of
                 if body_of[other] != body_of[name] and rank.get(other, len(free)) > rank[name]]
        for k, (a, b) in enumerate(pairs):
            spec.add_pair(name=f"pair{k}", geomname1=a, geomname2=b, condim=4)
        self._add_drives(spec)
        self._model = m = spec.compile()
        self._data = mujoco.MjData(m)
        # views of arrays read or written every step (the model and data live as long as these)
        self._qpos, self._qvel = self._data.qpos, self._data.qvel
        self._xpos, self._xquat = self._data.xpos, self._data.xquat
        self._xipos, self._ximat = self._data.xipos, self._data.ximat
        self._xfrc_applied = self._data.xfrc_applied
        self._jnt_range, self._jnt_solref = m.jnt_range, m.jnt_solref
        self._pair_geoms = np.stack([m.pair_geom1, m.pair_geom2], axis=1) if m.npair else (
            np.zeros((0, 2), int))
        self._friction = m.geom_friction[:, :2].copy()  # lateral, torsional arm (m), per geom
        self._index_bodies(m)
        self._loaded_ranges = m.jnt_range.copy()
        self._index_servos(m)
        self._index_drives(m)
        mujoco.mj_forward(m, self._data)
        self._update_pairs()

    def _index_servos(self, m: mujoco.MjModel) -> None:
        """The arm's servo constraints: equality ``k`` holds joint ``_servo_joint[k]``; their
        constraint rows come first in every step (MuJoCo orders equalities first)."""
        if m.neq != len(self._servo_names):
            raise ValueError(f"expected only the arm's {len(self._servo_names)} servo "
                             f"constraints, the model has {m.neq} equalities")
        joints = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, n) for n in self._servo_names]
        self._servo_of = {j: k for k, j in enumerate(joints)}
        self._servo_qpos = m.jnt_qposadr[joints].astype(int)
        self._servo_target = self._data.qpos[self._servo_qpos].copy()
        self._servo_from = self._servo_target.copy()
        self._servo_limit = np.full(len(joints), np.inf)
        self._servo_rows = slice(0, len(joints))
        self.servo_peak_n = np.zeros(len(joints))
        self._set_servo_stiffness(m)

    def _set_servo_stiffness(self, m: mujoco.MjModel) -> None:
        """Critically damped servos of ``SERVO_TIME_CONSTANT_S``, with a constant impedance
        (MuJoCo's damping over stiffness is then exactly twice the time constant, which the
        reference's lead in ``step`` relies on); and the hand motors' rows at
        ``STIFF_TIME_CONSTANT_S`` with ``DRIVE_IMPEDANCE``."""
        # MuJoCo stiffens no constraint beyond two physics steps (its refsafe)
        self._servo_time_constant = max(SERVO_TIME_CONSTANT_S, 2.0 * m.opt.timestep)
        m.eq_solref[:] = (self._servo_time_constant, 1.0)
        m.eq_solimp[:, :2] = m.eq_solimp[:, 1:2]
        self._substep_offsets = (np.arange(self.substeps) / self.substeps * self.timestep)[:, None]
        self._servo_references = m.eq_data[self._servo_rows, 0]
        m.tendon_solref_fri[:] = (self._stiff_time_constant(m), 1.0)
        m.tendon_solimp_fri[:, :2] = DRIVE_IMPEDANCE

    def _stiff_time_constant(self, m: mujoco.MjModel) -> float:
        """The stop's and the motors' time constant: ``STIFF_TIME_CONSTANT_S`` in a world stepped
        in the pads' substeps (a physics step of at most ``PAD_PHASE_PER_STEP`` over the pad's
        angular frequency, 1.13 ms: at least 1.48 physics steps), with MuJoCo's ``refsafe`` off,
        which would raise it to two steps (every other constraint's time constant is longer, or
        direct, so unaffected). A world without pads steps at the protocol's step, which cannot
        resolve it: there, two physics steps, MuJoCo's floor."""
        if self.substeps == 1:
            return max(STIFF_TIME_CONSTANT_S, 2.0 * m.opt.timestep)
        if 2.0 * m.opt.timestep > STIFF_TIME_CONSTANT_S:
            m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_REFSAFE
        return STIFF_TIME_CONSTANT_S

    def _index_bodies(self, m: mujoco.MjModel) -> None:
        self._body_ids: list[list[int]] = []
        self._joint_ids: list[list[int]] = []
        self._body_uid = np.full(m.nbody, -1)
        self._body_link = np.full(m.nbody, -2)
        for uid, (bodies, joints) in enumerate(zip(self._bodies, self._joints, strict=True)):
            ids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name) for name in bodies]
            self._body_ids.append(ids)
            self._body_uid[ids] = uid
            self._body_link[ids] = np.arange(-1, len(ids) - 1)
            self._joint_ids.append([-1 if name is None else
                                    mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
                                    for name in joints])

    def _body_id(self, body: int, link: int) -> int:
        self._compiled()
        return self._body_ids[body][link + 1]

    def _joint_id(self, body: int, joint: int) -> int:
        self._compiled()
        index = self._joint_ids[body][joint]
        if index < 0:
            raise ValueError(f"joint {joint} of body {body} is fixed")
        return index

    def _add_drives(self, spec: mujoco.MjSpec) -> None:
        """Each hand joint's motor: a reference joint of its own (a hinge of
        ``DRIVE_REFERENCE_INERTIA_KG_M2``, turned at the motor's target speed) and a fixed
        tendon ``q - q_ref`` whose friction loss, the motor's torque, holds the joint to it."""
        for k, name in enumerate(self._drive_names):
            body = spec.worldbody.add_body(name=f"drive{k}", mass=1.0, inertia=[1.0, 1.0, 1.0])
            body.explicitinertial = True
            body.add_joint(name=f"drive{k}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1],
                           armature=DRIVE_REFERENCE_INERTIA_KG_M2)
            tendon = spec.add_tendon(name=f"drive{k}", frictionloss=1.0)
            tendon.wrap_joint(name, 1.0)
            tendon.wrap_joint(f"drive{k}", -1.0)

    def _index_drives(self, m: mujoco.MjModel) -> None:
        """The hand's motors: drive ``k`` moves joint ``_drive_names[k]`` (tendon ``k``)."""
        if m.ntendon != len(self._drive_names):
            raise ValueError(f"expected only the hand's {len(self._drive_names)} drive tendons, "
                             f"the model has {m.ntendon}")
        joints = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, n) for n in self._drive_names]
        references = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f"drive{k}")
                      for k in range(len(joints))]
        self._drive_of = {j: k for k, j in enumerate(joints)}
        self._drive_qpos = m.jnt_qposadr[joints].astype(int)
        self._drive_reference_dof = m.jnt_dofadr[references].astype(int)
        self._drive_is_position = np.zeros(len(joints), bool)
        self._drive_command = np.zeros(len(joints))  # speed (rad/s) or target (rad)
        self._drive_gain = np.full(len(joints), DEFAULT_POSITION_GAIN)

    def _drives(self, body: int, joints: list[int]) -> NDArray[np.int64]:
        return np.array([self._drive_of[self._joint_id(body, j)] for j in joints], int)

    def _set_drive_torques(self, drives: NDArray[np.int64], torques: list[float]) -> None:
        self._model.tendon_frictionloss[drives] = np.abs(torques)

    def _set_drive_speeds(self, m: mujoco.MjModel, d: mujoco.MjData) -> None:
        """Each motor's reference speed for the coming protocol step: a velocity motor's target
        speed; a position motor's ``gain (target - q) / dt``, from the joint where it is now (as
        Bullet's motor, once a step)."""
        command = self._drive_command
        to_target = self._drive_gain * (command - d.qpos[self._drive_qpos]) / self.timestep
        d.qvel[self._drive_reference_dof] = np.where(self._drive_is_position, to_target, command)

    def drive_torques(self) -> NDArray[np.float64]:
        """The torque (N·m) each hand motor exerted on its joint in the last physics step (its
        tendon's friction-loss force; 0 for a motor without torque)."""
        m, d = self._compiled()
        rows = np.flatnonzero(d.efc_type[: d.nefc] == mujoco.mjtConstraint.mjCNSTR_FRICTION_TENDON)
        torques = np.zeros(m.ntendon)
        torques[d.efc_id[rows]] = d.efc_force[rows]
        return torques

    def _link_geoms(self, body: int, link: int) -> NDArray[np.int64]:
        m, _ = self._compiled()
        return np.flatnonzero(m.geom_bodyid == self._body_id(body, link))

    def _set_friction(self, body: int, link: int, lateral: float, torsion_m: float) -> None:
        m, _ = self._compiled()
        geoms = self._link_geoms(body, link)
        self._friction[geoms] = (lateral, torsion_m)
        m.geom_friction[geoms, 0] = lateral
        m.geom_friction[geoms, 1] = torsion_m
        self._update_pairs()

    def _update_pairs(self) -> None:
        """Every pair's friction as Bullet combines its two geoms' (product; torsion
        ``s0 mu1 + s1 mu0``), no rolling friction."""
        m = self._model
        if not m.npair:
            return
        a, b = self._friction[self._pair_geoms[:, 0]], self._friction[self._pair_geoms[:, 1]]
        lateral = a[:, 0] * b[:, 0]
        torsion = a[:, 1] * b[:, 0] + b[:, 1] * a[:, 0]
        m.pair_friction[:, 0] = lateral
        m.pair_friction[:, 1] = lateral
        m.pair_friction[:, 2] = np.maximum(torsion, mujoco.mjMINMU)
        m.pair_friction[:, 3:] = mujoco.mjMINMU


def pad_solref(stiffness_n_per_m: float, damping_n_s_per_m: float,
               inverse_weight: float) -> tuple[float, float]:
    """The direct ``solref`` that makes a contact of impedance ``PAD_IMPEDANCE`` and inverse
    weight ``inverse_weight`` (MuJoCo's ``efc_diagApprox`` of its normal: the two bodies'
    ``body_invweight0``) a spring of ``stiffness_n_per_m`` and a damper of ``damping_n_s_per_m``.

    MuJoCo (``mj_makeImpedance``; docs, "Computation: soft constraints"): a direct solref
    ``(-s, -c)`` gives the reference acceleration ``a_ref = -(s / d) r - (c / d) v`` (``k = s /
    d^2`` times the impedance ``d``, ``b = c / d``) and the contact force ``f = (a_ref - a) / R``
    with ``R = (1 - d) / d * A``. So ``f = -s / ((1 - d) A) r - c / ((1 - d) A) v - a / R``: a
    spring ``s / ((1 - d) A)``, a damper ``c / ((1 - d) A)`` and the inertia ``1 / R``
    (``PAD_IMPEDANCE``). At rest (``a = 0``) force over depth is exactly the spring.
    """
    scale = (1.0 - PAD_IMPEDANCE) * float(inverse_weight)
    return -stiffness_n_per_m * scale, -damping_n_s_per_m * scale


def _prism(piece: NDArray[np.float64], thickness_mm: float) -> list[list[float]]:
    """Vertices (m) of the prism of a convex piece from z = 0 to the top."""
    top = thickness_mm * MM
    return ([[x * MM, y * MM, 0.0] for x, y in piece]
            + [[x * MM, y * MM, top] for x, y in piece])


@functools.lru_cache(maxsize=256)  # every trial's world adds the same to the same links
def _with_axis_inertia(
    principal: bytes, axes: bytes, axis: int, added_kg_m2: float,
) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Principal inertia and axes (MuJoCo's quaternion) of the inertia ``principal`` about
    ``axes`` (float64 arrays' bytes: an exact key, telling -0.0 from 0.0) with ``added_kg_m2``
    added about the body frame's ``axis``."""
    rotation = np.empty(9)
    mujoco.mju_quat2Mat(rotation, np.frombuffer(axes))
    rotation = rotation.reshape(3, 3)  # principal axes in the link frame, as columns
    tensor = rotation @ np.diag(np.frombuffer(principal)) @ rotation.T
    tensor[axis, axis] += added_kg_m2
    values, vectors = np.linalg.eigh(tensor)
    if np.linalg.det(vectors) < 0:
        vectors[:, 0] = -vectors[:, 0]
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, vectors.ravel())
    return tuple(values.tolist()), tuple(quat.tolist())


@functools.cache  # the mounted URDF's path names its content (``mounted_urdf``)
def _urdf_joints(path: Path) -> tuple[list[tuple[str, str, str]], dict[str, str]]:
    """The URDF's joints in file order (PyBullet's joint indices here): name, type, child link;
    and each link's parent link (cached: do not modify)."""
    joints, parents = [], {}
    for joint in ET.parse(path).getroot().iter("joint"):
        child = joint.find("child").get("link")  # type: ignore[union-attr]
        parents[child] = joint.find("parent").get("link")  # type: ignore[union-attr]
        joints.append((joint.get("name"), joint.get("type"), child))
    return joints, parents  # type: ignore[return-value]


@functools.cache
def _urdf_root_link(path: Path) -> str:
    """The name of the URDF's first link, its root."""
    return ET.parse(path).getroot().find("link").get("name")  # type: ignore[union-attr]


__all__ = ["DRIVE_IMPEDANCE", "IMPRATIO", "MULTI_CONTACT", "NOSLIP_ITERATIONS",
           "PAD_IMPEDANCE", "SERVO_TIME_CONSTANT_S", "STIFF_TIME_CONSTANT_S", "MujocoWorld",
           "pad_solref"]
