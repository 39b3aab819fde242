"""``World``: one PyBullet client (headless) and the bodies every scene shares.

This module is the only place that calls pybullet (the PyBullet side of
``grip_env.sim.engine``). Geometry arrives in millimetres and leaves in
millimetres; metres exist only inside this layer.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from grip_env.objects import PlanarObject
from grip_env.objects.decomposition import MAX_PIECES
from grip_env.objects.simulated import DEFAULT_TOLERANCE_MM
from grip_env.shutdown import deferred_signals
from grip_env.sim.body import MM, Body
from grip_env.sim.gantry import mounted_urdf


@contextlib.contextmanager
def _quiet_native(*fds: int) -> Iterator[None]:
    """Silence what pybullet's C code prints to the file descriptors ``fds`` (1: ``argv[0]=``;
    2: the ``pybullet build time`` banner of the import)."""
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = [os.dup(fd) for fd in fds]
    except (OSError, ValueError):
        yield
        return
    try:
        with open(os.devnull, "w") as devnull:
            for fd in fds:
                os.dup2(devnull.fileno(), fd)
            yield
    finally:
        for fd, copy in zip(fds, saved, strict=True):
            os.dup2(copy, fd)
            os.close(copy)


with _quiet_native(1, 2):
    import pybullet
    from pybullet_utils.bullet_client import BulletClient

COLLISION_MARGIN_MM = 1.0
"""Bullet's margin around a convex mesh (PyBullet 3.2.7's default, measured: exact prisms touched a
probe 1 mm away; ``changeDynamics(collisionMargin=)`` changes the base only, not links). Object
prisms are built eroded by it (``SimulatedShape.collision_pieces``) so that they collide as the
shape itself."""


class World:
    """A headless PyBullet world owning its own client; use as a context manager or ``close()``."""

    #: ``restore`` finds the contacts afresh, so a paused moment cannot be resumed bit for bit.
    resumes_exactly = False

    def __init__(self, timestep: float = 1.0 / 240.0, solver_iterations: int = 50) -> None:
        # A stop signal during the connection would leave a half-built client whose finaliser
        # fails noisily at exit: the connection is made whole first, then the signal acts.
        with deferred_signals(), _quiet_native(1):
            self.client = BulletClient(connection_mode=pybullet.DIRECT)
        self.timestep = timestep
        self.solver_iterations = solver_iterations
        self._bind()
        self.reset()

    def _bind(self) -> None:
        """Hold the client functions the per-step loop calls (``BulletClient`` builds a new
        partial at every attribute lookup)."""
        c = self.client
        self._step_simulation = c.stepSimulation
        self._get_joint_states = c.getJointStates
        self._change_dynamics = c.changeDynamics
        self._base_pose = c.getBasePositionAndOrientation
        self._link_state = c.getLinkState
        self._motor_array = c.setJointMotorControlArray
        self._external_force = c.applyExternalForce
        self._external_torque = c.applyExternalTorque

    # ------------------------------------------------------------------ lifecycle
    def reset(self) -> None:
        """Empty the world and restore gravity and solver settings."""
        c = self.client
        c.resetSimulation()
        c.setGravity(0, 0, -9.81)
        # Deterministic overlapping pairs: contacts are solved in an order that does not depend
        # on the history of the broadphase, so a restored state replays exactly (trial order).
        # No position correction on joint limits and constraints (erp 0): the worm gear's stops
        # (joint floors) must hold a finger, never push it forward; a correction towards a floor
        # pumped squeeze into the grip that grew with the iteration count (BENCHMARKS.md). The
        # arm's motors keep their own gains; contacts keep their own correction (contactERP).
        c.setPhysicsEngineParameter(
            fixedTimeStep=self.timestep, numSolverIterations=self.solver_iterations,
            deterministicOverlappingPairs=1, erp=0.0,
        )

    def close(self) -> None:
        """Disconnect the client (idempotent)."""
        if getattr(self, "client", None) is not None:
            with contextlib.suppress(pybullet.error):
                self.client.disconnect()
            self.client = None

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        self.close()

    def step(self, steps: int = 1) -> None:
        """Advance the simulation ``steps`` fixed steps."""
        step = self._step_simulation
        for _ in range(steps):
            step()

    # ------------------------------------------------------------------ bodies
    def add_table(self, friction: float = 0.5, half_size_mm: float = 500.0) -> Body:
        """A static table whose top face is at z = 0."""
        c = self.client
        half = [half_size_mm * MM, half_size_mm * MM, 0.01]
        shape = c.createCollisionShape(pybullet.GEOM_BOX, halfExtents=half)
        visual = c.createVisualShape(pybullet.GEOM_BOX, halfExtents=half, rgbaColor=[1, 1, 1, 1])
        uid = c.createMultiBody(0, shape, visual, basePosition=[0, 0, -0.01])
        c.changeDynamics(uid, -1, lateralFriction=friction)
        return Body(uid, 0.0)

    def add_object(
        self,
        obj: PlanarObject,
        thickness_mm: float = 30.0,
        mass_kg: float = 0.3,
        friction: float = 0.5,
        rgba: tuple[float, float, float, float] = (0.15, 0.15, 0.15, 1.0),
        tolerance_mm: float = DEFAULT_TOLERANCE_MM,
    ) -> Body:
        """The object extruded to ``thickness_mm`` on z = 0, one prism per convex piece of its
        simulated shape (within ``tolerance_mm`` of the contour; ``objects.sim_tolerance_mm``).

        Raises:
            ValueError: bad thickness or mass, or a shape that cannot be simulated whole.

        The body frame is the object's plane frame (x, y in mm scaled to m, origin at the plane
        origin), so planar coordinates map to world coordinates without a transform.
        """
        if thickness_mm <= 0 or mass_kg <= 0:
            raise ValueError(f"thickness and mass must be positive, got {thickness_mm}, {mass_kg}")
        if thickness_mm <= 2 * COLLISION_MARGIN_MM:
            raise ValueError(f"thickness must exceed {2 * COLLISION_MARGIN_MM:g} mm, "
                             f"twice the collision margin, got {thickness_mm}")
        c = self.client
        shape = obj.simulated_shape(tolerance_mm)
        shapes = [
            c.createCollisionShape(pybullet.GEOM_MESH, vertices=_collision_prism(p, thickness_mm))
            for p in shape.collision_pieces(COLLISION_MARGIN_MM)
        ]
        visuals = [_visual_prism(c, piece, thickness_mm, rgba) for piece in shape.pieces]
        links = max(len(shapes), len(visuals))  # a link may carry only one of the two
        shapes += [-1] * (links - len(shapes))
        visuals += [-1] * (links - len(visuals))
        centroid = [obj.centroid[0] * MM, obj.centroid[1] * MM, thickness_mm * MM / 2]
        inertia, axes = prism_inertia(obj, thickness_mm)
        uid = self._compound(shapes, visuals, mass_kg, centroid, axes)
        body = Body(uid, thickness_mm, tuple(range(-1, len(shapes) - 1)), inertia)
        self.set_dynamics(body, mass_kg, friction)
        return body

    def add_mesh(
        self, path: str | Path, scale: float, com_mm: NDArray[np.float64],
        position_mm: NDArray[np.float64], orientation: tuple[float, float, float, float],
        mass_kg: float, friction: float, inertia_per_kg: tuple[float, float, float],
        axes: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0),
        rgba: tuple[float, float, float, float] = (0.15, 0.15, 0.15, 1.0),
    ) -> Body:
        """A mesh file as one dynamic body: one convex hull per object (``o``/``g``) of the
        OBJ file (PyBullet's own convex decomposition of a VHACD file), its vertices scaled by
        ``scale`` (mm per mesh unit), its centre of mass ``com_mm`` (mesh frame, mm) placed at
        ``position_mm`` and the mesh frame turned by ``orientation`` (x, y, z, w); principal
        inertia per kg (m²) about ``axes`` (mesh frame). ``top_mm``: the top of its bounding box
        (Bullet grows every hull by its collision margin, ``COLLISION_MARGIN_MM``).
        ``pose_mm`` then gives the centre of mass and ``orientation`` times ``axes``.
        """
        if mass_kg <= 0 or scale <= 0:
            raise ValueError(f"mesh scale and mass must be positive, got {scale}, {mass_kg}")
        c = self.client
        size = [scale * MM] * 3
        shape = c.createCollisionShape(pybullet.GEOM_MESH, fileName=str(path), meshScale=size)
        visual = c.createVisualShape(pybullet.GEOM_MESH, fileName=str(path), meshScale=size,
                                     rgbaColor=list(rgba))
        rotation = np.asarray(c.getMatrixFromQuaternion(list(orientation))).reshape(3, 3)
        origin = np.asarray(position_mm, float) - rotation @ np.asarray(com_mm, float)
        uid = c.createMultiBody(mass_kg, shape, visual, basePosition=(origin * MM).tolist(),
                                baseOrientation=list(orientation),
                                baseInertialFramePosition=(np.asarray(com_mm) * MM).tolist(),
                                baseInertialFrameOrientation=list(axes))
        top = c.getAABB(uid)[1][2] / MM
        body = Body(uid, float(top), (-1,), tuple(map(float, inertia_per_kg)))  # type: ignore[arg-type]
        self.set_dynamics(body, mass_kg, friction)
        return body

    def add_sphere(
        self, radius_mm: float, mass_kg: float, friction: float, position_mm: NDArray[np.float64],
        inertia_kg_m2: float | None = None,
        rgba: tuple[float, float, float, float] = (0.15, 0.15, 0.15, 1.0),
    ) -> Body:
        """A free sphere centred at ``position_mm``, of inertia ``inertia_kg_m2`` about every axis
        (a uniform ball's, 2/5 m r², if None); ``top_mm`` is its top. Bullet's sphere is exact:
        its collision margin is its radius.

        Raises:
            ValueError: a radius, mass or inertia that is not positive.
        """
        inertia = sphere_inertia_per_kg(radius_mm, mass_kg, inertia_kg_m2)
        c = self.client
        shape = c.createCollisionShape(pybullet.GEOM_SPHERE, radius=radius_mm * MM)
        visual = c.createVisualShape(pybullet.GEOM_SPHERE, radius=radius_mm * MM,
                                     rgbaColor=list(rgba))
        position = (np.asarray(position_mm, float) * MM).tolist()
        uid = c.createMultiBody(mass_kg, shape, visual, basePosition=position)
        body = Body(uid, float(position_mm[2]) + radius_mm, (-1,), inertia)
        self.set_dynamics(body, mass_kg, friction)
        return body

    def set_dynamics(self, body: Body, mass_kg: float, friction: float,
                     spinning_friction: float = 0.0) -> None:
        """Mass (with the whole body's inertia) and friction on every link of ``body``.

        Bullet combines two touching bodies' lateral frictions as the product mu0 * mu1, so
        ``friction`` is the object's side of the product (the pads' is 1); it combines their
        spinning (torsional) frictions as s0 * mu1 + s1 * mu0 (btManifoldResult). With the
        object's ``spinning_friction`` 0, a pad of torsional arm s gives the pair mu * s: the
        torque a contact resists is mu * N * s, as for a real pad (``sim.pad_torsion_mm``).
        Every convex piece gets the same values.
        """
        c = self.client
        inertia = [i * mass_kg for i in body.inertia_per_kg]
        c.changeDynamics(body.uid, -1, mass=mass_kg, localInertiaDiagonal=inertia)
        for link in body.links:
            c.changeDynamics(body.uid, link, lateralFriction=friction,
                             spinningFriction=spinning_friction, rollingFriction=0.0)

    def _compound(
        self, shapes: list[int], visuals: list[int], mass_kg: float, com: list[float],
        axes: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0),
    ) -> int:
        c = self.client
        n = len(shapes)
        if n > MAX_PIECES:
            raise ValueError(
                f"a body of {n} convex pieces exceeds PyBullet's {MAX_PIECES} (base + 127 links)"
            )
        if n == 1:
            return c.createMultiBody(
                mass_kg, shapes[0], visuals[0], basePosition=[0, 0, 0],
                baseInertialFramePosition=com, baseInertialFrameOrientation=axes,
            )
        # A massless-looking base is avoided: the whole mass sits in the base, links are fixed.
        return c.createMultiBody(
            baseMass=mass_kg,
            baseCollisionShapeIndex=shapes[0],
            baseVisualShapeIndex=visuals[0],
            basePosition=[0, 0, 0],
            baseInertialFramePosition=com,
            baseInertialFrameOrientation=axes,
            linkMasses=[0.0] * (n - 1),
            linkCollisionShapeIndices=shapes[1:],
            linkVisualShapeIndices=visuals[1:],
            linkPositions=[[0, 0, 0]] * (n - 1),
            linkOrientations=[[0, 0, 0, 1]] * (n - 1),
            linkInertialFramePositions=[[0, 0, 0]] * (n - 1),
            linkInertialFrameOrientations=[[0, 0, 0, 1]] * (n - 1),
            linkParentIndices=[0] * (n - 1),
            linkJointTypes=[pybullet.JOINT_FIXED] * (n - 1),
            linkJointAxis=[[0, 0, 1]] * (n - 1),
        )

    def pose_mm(self, body: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Position (mm) and quaternion (x, y, z, w) of a body's base (its centre of mass)."""
        pos, orn = self._base_pose(body)
        return np.asarray(pos) / MM, np.asarray(orn)

    def pose_floats_mm(
        self, body: int
    ) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
        """``pose_mm`` as plain tuples (for per-step checks)."""
        (x, y, z), orn = self._base_pose(body)
        return (x / MM, y / MM, z / MM), orn

    # ------------------------------------------------------------------ robots
    def load_robot(self, urdf: str | Path) -> int:
        """A URDF mounted on the gantry arm (``grip_env.sim.gantry``), fixed to the world, with its
        own inertia and self-collision (between links that are not ancestors)."""
        flags = (pybullet.URDF_USE_INERTIA_FROM_FILE | pybullet.URDF_USE_SELF_COLLISION
                 | pybullet.URDF_USE_SELF_COLLISION_EXCLUDE_ALL_PARENTS)
        return self.client.loadURDF(str(mounted_urdf(urdf)), useFixedBase=True, flags=flags)

    def link_count(self, body: int) -> int:
        """Number of links (= joints) of ``body``, the base not counted."""
        return self.client.getNumJoints(body)

    def link_pose_floats_mm(
        self, body: int, link: int
    ) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
        """Position (mm) and quaternion of a link's frame (its URDF frame, not its centre of
        mass), computed from the current joint positions."""
        state = self._link_state(body, link, computeForwardKinematics=1)
        x, y, z = state[4]
        return (x / MM, y / MM, z / MM), state[5]

    def add_axis_inertia(self, body: int, link: int, axis: int, inertia_kg_m2: float) -> None:
        """Add ``inertia_kg_m2`` to a link's principal inertia about its local ``axis`` (0, 1, 2):
        a joint's reflected rotor inertia when that axis is parallel to the joint's."""
        diagonal = list(self.client.getDynamicsInfo(body, link)[2])
        diagonal[axis] += inertia_kg_m2
        self.client.changeDynamics(body, link, localInertiaDiagonal=diagonal)

    def set_pad_friction(self, body: int, link: int, lateral: float, torsion_mm: float) -> None:
        """Friction of one link: lateral coefficient, torsional friction (torque per normal
        force, mm), with a friction anchor so resting contacts do not drift."""
        self.client.changeDynamics(body, link, lateralFriction=lateral,
                                   spinningFriction=torsion_mm * MM, frictionAnchor=1)

    def set_contact_compliance(self, body: int, link: int, stiffness_n_per_m: float,
                               damping_n_s_per_m: float) -> None:
        """Make one link's contacts compliant: each contact point presses with ``k d + c v``
        (penetration d, its rate v), solved implicitly (Bullet's contact CFM and ERP), instead of
        being pushed out by the position correction of a rigid contact."""
        self.client.changeDynamics(body, link, contactStiffness=stiffness_n_per_m,
                                   contactDamping=damping_n_s_per_m)

    def set_joint(self, body: int, joint: int, position: float) -> None:
        """Teleport one joint (rad), at rest."""
        self.client.resetJointState(body, joint, float(position))

    def velocity_motors(self, body: int, joints: list[int], speeds: list[float],
                        torques: list[float]) -> None:
        """Velocity-controlled joint motors of limited torque (N·m)."""
        self._motor_array(body, joints, pybullet.VELOCITY_CONTROL, targetVelocities=speeds,
                          forces=torques)

    def position_motors(self, body: int, joints: list[int], targets: list[float],
                        torques: list[float], gain: float | None = None) -> None:
        """Position-controlled joint motors of limited torque (N·m); PyBullet's gain if None."""
        gains = {} if gain is None else {"positionGains": [gain] * len(joints)}
        self._motor_array(body, joints, pybullet.POSITION_CONTROL, targetPositions=targets,
                          forces=torques, **gains)

    def joint_floors(self, body: int, joints: list[int], lowers: list[float],
                     uppers: list[float], holds: list[float]) -> None:
        """Raise (or lower) joints' lower limits: one-sided stops of ``holds`` N·m each
        (``math.inf``: any load).

        A joint limit is a unilateral constraint solved together with the contacts and motors
        (measured: a thumb at its floor, pushed back by 40 N, about 3x its motor, gives 0.02
        mrad; a stop weaker than the load yields). With ``erp`` 0 (``reset``) a joint the solver
        let slip below its limit stays there: the stop resists, it never pushes the joint
        forward. ``saveState`` does not keep limits.
        """
        change = self._change_dynamics
        for joint, low, high, hold in zip(joints, lowers, uppers, holds, strict=True):
            change(body, joint, jointLowerLimit=low, jointUpperLimit=high, jointLimitForce=hold)

    def joint_limits(self, body: int, joint: int) -> tuple[float, float]:
        """A joint's lower and upper limits (rad) as loaded (the URDF's)."""
        info = self.client.getJointInfo(body, joint)
        return float(info[8]), float(info[9])

    def joint_states(
        self, body: int, joints: list[int]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Positions, velocities and applied motor torques of ``joints``."""
        states = self._get_joint_states(body, joints)
        return tuple(np.array([s[k] for s in states]) for k in (0, 1, 3))  # type: ignore[return-value]

    def joint_positions_velocities(self, body: int,
                                   joints: list[int]) -> tuple[list[float], list[float]]:
        """Positions and velocities of ``joints``, as lists (for the per-step controller)."""
        states = self._get_joint_states(body, joints)
        return [s[0] for s in states], [s[1] for s in states]

    def joint_positions(self, body: int, joints: list[int]) -> list[float]:
        """Positions of ``joints``, as a list (for the per-step controller)."""
        return [state[0] for state in self._get_joint_states(body, joints)]

    def touching_links(self, body: int, other: int) -> set[int]:
        """The links of ``body`` in contact with ``other``."""
        return {point[3] for point in self.client.getContactPoints(bodyA=body, bodyB=other)}

    def contact_normal_force_n(self, body: int, other: int) -> float:
        """The sum of the normal forces (N) of ``body``'s contacts with ``other`` in the last
        step."""
        points = self.client.getContactPoints(bodyA=body, bodyB=other)
        return float(sum(point[9] for point in points))

    def set_gravity(self, gravity: tuple[float, float, float]) -> None:
        """Gravity (m/s², world frame); ``reset`` restores 9.81 down."""
        self.client.setGravity(*gravity)

    # ------------------------------------------------------------------ states and loads
    def save(self) -> int:
        """Save the whole world in memory; returns a state id (``restore``, ``forget``)."""
        return self.client.saveState()

    def restore(self, state: int) -> None:
        """Return the world to a saved state, the same whatever happened since it was saved.

        Bullet's ``restoreState`` restores every body and joint exactly, but writes the saved
        contact points into the contact manifolds as they are when it is called: a fingertip
        restored to a held grip kept points of the moment beside the saved ones, each a whole
        pad spring (the squeeze up to twice the hand's), and each restore began from a
        different state, set by what ran before it. After the bodies are restored, every
        manifold is emptied and the contacts are found afresh at the restored poses, as if the
        world had been built there (``tests/test_engine_physics.py``; BENCHMARKS.md, "A restore
        that keeps no contact of the moment").
        """
        self.client.restoreState(state)
        self._renew_contacts()

    def pause(self) -> int:
        """``save``: a moment to ``restore`` or ``resume`` before the next step."""
        return self.save()

    def resume(self, state: int) -> None:
        """``restore``: PyBullet cannot resume a moment bit for bit (``resumes_exactly``)."""
        self.restore(state)

    def _renew_contacts(self) -> None:
        """Empty every contact manifold that holds points (their pairs kept from colliding for
        one collision pass), then find the contacts at the present poses."""
        c = self.client
        pairs = sorted({point[1:5] for point in c.getContactPoints()})
        for a, b, link_a, link_b in pairs:
            c.setCollisionFilterPair(a, b, link_a, link_b, 0)
        c.performCollisionDetection()
        for a, b, link_a, link_b in pairs:
            c.setCollisionFilterPair(a, b, link_a, link_b, 1)
        c.performCollisionDetection()

    def forget(self, state: int) -> None:
        """Free a saved state."""
        self.client.removeState(state)

    def push(self, body: int, force_n: NDArray) -> None:
        """A world-frame force (N) through ``body``'s centre of mass, for the next step."""
        com = self._base_pose(body)[0]
        self._external_force(body, -1, np.asarray(force_n).tolist(), com, pybullet.WORLD_FRAME)

    def twist(self, body: int, torque_nm: NDArray) -> None:
        """A world-frame torque (N·m) on ``body``, for the next step."""
        self._external_torque(body, -1, np.asarray(torque_nm).tolist(), pybullet.WORLD_FRAME)

    # ------------------------------------------------------------------ camera
    def set_colour(self, body: Body, rgba: tuple[float, float, float, float]) -> None:
        """Paint every visual link of ``body`` in ``rgba`` (its look only: no physics changes)."""
        c = self.client
        for _, link, *_ in c.getVisualShapeData(body.uid):
            c.changeVisualShape(body.uid, link, rgbaColor=list(rgba))

    def render_top_down(
        self, center_mm: NDArray[np.float64], resolution_px: int, mm_per_px: float,
        plane_z_mm: float = 0.0, height_mm: float = 1000.0,
    ) -> NDArray[np.uint8]:
        """Top-down grey image of the plane z = ``plane_z_mm``, centred on ``center_mm``.

        Row 0 is at +y. The scale ``mm_per_px`` holds exactly on that plane (the object's top face).

        A narrow field of view from high up makes the perspective negligible; pixel (r, c)
        looks at x = cx + (c + 0.5 - n/2) s, y = cy - (r + 0.5 - n/2) s with s = mm_per_px.
        """
        c = self.client
        n = resolution_px
        half_extent_m = n * mm_per_px * MM / 2
        eye_height = height_mm * MM
        # The tiny renderer samples pixel corners, half a pixel towards -x, -y of the centres:
        # shift the camera by half a pixel so that the pixel-centre convention above holds.
        cx, cy = (center_mm[0] + mm_per_px / 2) * MM, (center_mm[1] + mm_per_px / 2) * MM
        plane_z = plane_z_mm * MM
        view = c.computeViewMatrix([cx, cy, plane_z + eye_height], [cx, cy, plane_z], [0, 1, 0])
        fov = 2 * np.degrees(np.arctan(half_extent_m / eye_height))
        projection = c.computeProjectionMatrixFOV(fov, 1.0, eye_height * 0.5, eye_height * 1.5)
        _, _, rgba, _, _ = c.getCameraImage(
            n, n, view, projection, renderer=pybullet.ER_TINY_RENDERER, shadow=0,
            lightDirection=[0, 0, 1],
        )
        rgb = np.asarray(rgba, dtype=np.uint8).reshape(n, n, 4)[..., :3]
        return rgb.mean(axis=2).astype(np.uint8)


    def render(
        self, eye_mm: NDArray[np.float64], target_mm: NDArray[np.float64],
        width: int = 320, height: int = 240, fov_deg: float = 50.0,
    ) -> NDArray[np.uint8]:
        """RGB image (height, width, 3) seen from ``eye_mm`` towards ``target_mm`` (z up)."""
        if width < 1 or height < 1:
            raise ValueError(f"image size must be positive, got {width} x {height}")
        c = self.client
        eye = (np.asarray(eye_mm, float) * MM).tolist()
        target = (np.asarray(target_mm, float) * MM).tolist()
        view = c.computeViewMatrix(eye, target, [0, 0, 1])
        distance = float(np.linalg.norm(np.subtract(eye, target)))
        projection = c.computeProjectionMatrixFOV(
            fov_deg, width / height, distance * 0.05, distance * 10
        )
        _, _, rgba, _, _ = c.getCameraImage(
            width, height, view, projection, renderer=pybullet.ER_TINY_RENDERER
        )
        return np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[..., :3]


def prism_inertia(
    obj: PlanarObject, thickness_mm: float
) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    """Principal inertia per kg (m²) of the uniform prism and its principal axes (quaternion).

    From the whole polygon's second central moments: about the in-plane principal axes
    ``l_other + t²/12``, about z ``l1 + l2``; the axes turn about z by the major axis angle.
    """
    l_minor, l_major = np.linalg.eigvalsh(obj.second_moments) * MM**2
    t2 = (thickness_mm * MM) ** 2 / 12.0
    inertia = (float(l_minor + t2), float(l_major + t2), float(l_major + l_minor))
    half = obj.major_axis_angle / 2.0
    return inertia, (0.0, 0.0, float(np.sin(half)), float(np.cos(half)))


def sphere_inertia_per_kg(radius_mm: float, mass_kg: float,
                           inertia_kg_m2: float | None) -> tuple[float, float, float]:
    """A sphere's principal inertia per kg (m²): ``inertia_kg_m2`` about every axis, or a uniform
    ball's 2/5 r² if None.

    Raises:
        ValueError: a radius, mass or inertia that is not positive.
    """
    if radius_mm <= 0 or mass_kg <= 0 or (inertia_kg_m2 is not None and inertia_kg_m2 <= 0):
        raise ValueError(f"a sphere's radius, mass and inertia must be positive, got "
                         f"{radius_mm}, {mass_kg}, {inertia_kg_m2}")
    per_kg = 0.4 * (radius_mm * MM) ** 2 if inertia_kg_m2 is None else inertia_kg_m2 / mass_kg
    return (per_kg, per_kg, per_kg)


def _collision_prism(piece: NDArray[np.float64], thickness_mm: float) -> list[list[float]]:
    """Prism vertices (m) of an eroded piece, its faces a collision margin in from z = 0 and the
    top: Bullet grows it back by the margin to the object's own faces."""
    low, high = COLLISION_MARGIN_MM * MM, (thickness_mm - COLLISION_MARGIN_MM) * MM
    return [[x * MM, y * MM, low] for x, y in piece] + [[x * MM, y * MM, high] for x, y in piece]


def _prism(piece: NDArray[np.float64], thickness_mm: float) -> list[list[float]]:
    bottom = [[x * MM, y * MM, 0.0] for x, y in piece]
    top = [[x * MM, y * MM, thickness_mm * MM] for x, y in piece]
    return bottom + top


def _visual_prism(
    client: BulletClient, piece: NDArray[np.float64], thickness_mm: float,
    rgba: tuple[float, float, float, float],
) -> int:
    n = len(piece)
    vertices = _prism(piece, thickness_mm)
    indices: list[int] = []
    for i in range(1, n - 1):  # top and bottom fans
        indices += [n, n + i, n + i + 1]
        indices += [0, i + 1, i]
    for i in range(n):  # sides
        j = (i + 1) % n
        indices += [i, j, n + j, i, n + j, n + i]
    return client.createVisualShape(
        pybullet.GEOM_MESH, vertices=vertices, indices=indices, rgbaColor=list(rgba)
    )
