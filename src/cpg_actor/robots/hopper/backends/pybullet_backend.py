"""PyBullet backend (the paper's simulator): K hoppers in PyBullet worlds of up to 16 robots.

The robots of a world (one DIRECT client) stand at the same place on one ground plane;
collision filtering lets every foot touch the ground and nothing else, so they never interact
and each one behaves exactly as a robot alone in its world (bit for bit). One ``stepSimulation``
per world advances its robots. Bullet's cost per robot grows with the number of robots in one
world beyond about 16, hence several small worlds. PyBullet holds the GIL, so threads would
not help: for more throughput use the MuJoCo backend (or several processes).

Set-up that makes PyBullet match the robot description and the MuJoCo backend:
``URDF_USE_INERTIA_FROM_FILE`` (else PyBullet recomputes inertias from shapes), default
velocity motors disabled (``VELOCITY_CONTROL`` with zero force), link and joint damping 0,
joint torques by ``TORQUE_CONTROL`` before every substep, ground lateral friction 1 (Bullet
multiplies the two frictions, so the foot's value is the pair's).
"""

from __future__ import annotations

import contextlib
import os
import sys

import numpy as np


@contextlib.contextmanager
def quiet_stdout():
    """Silence C-level prints on file descriptors 1 and 2 (PyBullet's banner, URDF chatter)."""
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = [os.dup(1), os.dup(2)]
    except (AttributeError, OSError, ValueError):  # no real stdout: nothing to silence
        yield
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)
    os.close(devnull)
    try:
        yield
    finally:
        _flush_c_stdio()  # printf output sits in C's buffer: flush it while it goes nowhere
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        os.close(saved[0])
        os.close(saved[1])


def _flush_c_stdio() -> None:
    try:
        import ctypes

        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError, TypeError):
        pass


with quiet_stdout():
    import pybullet
    from pybullet_utils import bullet_client

from cpg_actor.robots.common.actuator import Actuator  # noqa: E402
from cpg_actor.robots.common.backend import Backend  # noqa: E402
from cpg_actor.robots.hopper import description as robot  # noqa: E402
from cpg_actor.robots.hopper.urdf import URDF_PATH  # noqa: E402

RAIL, HFE, KFE = 0, 1, 2  # joint indices in the URDF (the adapter's fixed joint is 3)
HIP_LINK = 0  # the rail joint's child: the hip, which a payload and a push act on
FOOT_LINK = 3  # the adapter link carries the foot sphere
ROBOTS_PER_WORLD = 16  # Bullet's cost per robot grows with the robots sharing a spot
_FOOT_GROUP, _GROUND_GROUP = 0x1, 0x2


class _World:
    """One PyBullet DIRECT client: a ground plane and up to ROBOTS_PER_WORLD hoppers."""

    def __init__(self, num_robots: int, physics_dt: float, foot_friction: float,
                 payload: float = 0.0) -> None:  # fmt: skip
        self.num_robots = num_robots
        self.physics_dt = physics_dt
        # each robot's foot friction and payload (one for all but under randomised training)
        self.foot_friction = [foot_friction] * num_robots
        self.payload = [payload] * num_robots
        with quiet_stdout():
            self.client = bullet_client.BulletClient(connection_mode=pybullet.DIRECT)
        self.poisoned = False  # a NaN reached Bullet: rebuild before the next use
        self.build()

    def build(self) -> None:
        c = self.client
        c.resetSimulation()
        c.setGravity(0.0, 0.0, -robot.GRAVITY)
        c.setPhysicsEngineParameter(
            fixedTimeStep=self.physics_dt, numSubSteps=0, deterministicOverlappingPairs=1
        )
        plane_shape = c.createCollisionShape(pybullet.GEOM_PLANE)
        plane_visual = c.createVisualShape(
            pybullet.GEOM_BOX, halfExtents=[2.0, 2.0, 0.001], visualFramePosition=[0, 0, -0.001],
            rgbaColor=[0.7, 0.72, 0.75, 1.0],
        )  # fmt: skip
        self.ground = c.createMultiBody(0.0, plane_shape, plane_visual)
        c.changeDynamics(self.ground, -1, lateralFriction=1.0, restitution=0.0)
        c.setCollisionFilterGroupMask(self.ground, -1, _GROUND_GROUP, _FOOT_GROUP)
        rail_visual = c.createVisualShape(
            pybullet.GEOM_CYLINDER, radius=0.01, length=1.2, rgbaColor=[0.5, 0.5, 0.55, 1.0]
        )
        c.createMultiBody(0.0, -1, rail_visual, basePosition=[-0.03, 0.0, 0.6])  # looks only
        self.bodies = []
        for _ in range(self.num_robots):
            with quiet_stdout():
                body = c.loadURDF(
                    str(URDF_PATH), useFixedBase=True, flags=pybullet.URDF_USE_INERTIA_FROM_FILE
                )
            for link in range(c.getNumJoints(body)):
                c.changeDynamics(
                    body, link, linearDamping=0.0, angularDamping=0.0, jointDamping=0.0,
                    maxJointVelocity=1000.0, restitution=0.0,
                )  # fmt: skip
                c.setCollisionFilterGroupMask(body, link, 0, 0)
            self.hip_mass = c.getDynamicsInfo(body, HIP_LINK)[0]
            self.perturb(len(self.bodies), body)
            c.setCollisionFilterGroupMask(body, FOOT_LINK, _FOOT_GROUP, _GROUND_GROUP)
            c.setJointMotorControlArray(
                body, [RAIL, HFE, KFE], pybullet.VELOCITY_CONTROL, forces=[0.0, 0.0, 0.0]
            )
            self.bodies.append(body)
        names = [c.getJointInfo(self.bodies[0], j)[1].decode() for j in (RAIL, HFE, KFE)]
        if names != [robot.RAIL_JOINT, *robot.JOINT_NAMES]:
            raise RuntimeError(f"unexpected joint order in {URDF_PATH}: {names}")
        self.poisoned = False

    def perturb(self, local: int, body: int | None = None) -> None:
        """Robot ``local`` of this world with its foot friction and payload (at the hip's
        centre of mass: the hip's inertia about it unchanged)."""
        c = self.client
        body = self.bodies[local] if body is None else body
        c.changeDynamics(body, FOOT_LINK, lateralFriction=self.foot_friction[local])
        if self.payload[local] or c.getDynamicsInfo(body, HIP_LINK)[0] != self.hip_mass:
            c.changeDynamics(body, HIP_LINK, mass=self.hip_mass + self.payload[local])

    def close(self) -> None:
        try:
            self.client.disconnect()
        except pybullet.error:
            pass


class PybulletBackend(Backend):
    name = "pybullet"

    def __init__(
        self,
        actuator: Actuator,
        physics_dt: float,
        foot_friction: float,
        num_robots: int = 1,
        num_threads: int | None = None,  # accepted for interface symmetry; unused
        payload: float = 0.0,
    ) -> None:
        self.actuator = actuator
        self.num_robots = int(num_robots)
        self.num_threads = 1
        sizes = [
            min(ROBOTS_PER_WORLD, self.num_robots - start)
            for start in range(0, self.num_robots, ROBOTS_PER_WORLD)
        ]
        self._worlds = [_World(size, float(physics_dt), float(foot_friction), float(payload))
                        for size in sizes]  # fmt: skip
        self.qpos = np.zeros((self.num_robots, 3))
        self.qvel = np.zeros((self.num_robots, 3))
        self._unstable = np.zeros(self.num_robots, dtype=bool)
        self.strength = np.ones((self.num_robots, 1))  # per robot (randomised training)

    def perturb_robots(self, index: np.ndarray, payload: np.ndarray, friction: np.ndarray,
                       strength: np.ndarray) -> None:  # fmt: skip
        """Each robot of ``index`` with its payload, foot friction and motor strength (its
        torques scaled: the actuator law is homogeneous in the drive's strength)."""
        for row, i in enumerate(np.atleast_1d(index)):
            world, local = self._worlds[i // ROBOTS_PER_WORLD], i % ROBOTS_PER_WORLD
            world.payload[local] = float(payload[row])
            world.foot_friction[local] = float(friction[row])
            world.perturb(local)
            self.strength[i] = strength[row]

    def handle(self, index: int) -> tuple[bullet_client.BulletClient, int]:
        """(client, body id) of robot ``index``, for diagnostics and tests."""
        world = self._worlds[index // ROBOTS_PER_WORLD]
        return world.client, world.bodies[index % ROBOTS_PER_WORLD]

    def _robots(self):
        """(robot index, client, body id) for every robot, in order."""
        index = 0
        for world in self._worlds:
            for body in world.bodies:
                yield index, world.client, body
                index += 1

    # -- state -----------------------------------------------------------------------------
    def _read(self) -> None:
        qpos, qvel = self.qpos, self.qvel
        for i, c, body in self._robots():
            states = c.getJointStates(body, (RAIL, HFE, KFE))
            qpos[i] = (states[0][0], states[1][0], states[2][0])
            qvel[i] = (states[0][1], states[1][1], states[2][1])
        finite = np.isfinite(qpos).all(axis=1) & np.isfinite(qvel).all(axis=1)
        if not finite.all():
            self._unstable |= ~finite
            for i in np.flatnonzero(~finite):
                self._worlds[i // ROBOTS_PER_WORLD].poisoned = True

    def reset_robots(self, index: np.ndarray, qpos: np.ndarray, qvel: np.ndarray) -> None:
        index = np.atleast_1d(np.asarray(index, dtype=np.int64))
        for w, world in enumerate(self._worlds):
            if not world.poisoned:
                continue
            # NaNs can stay in Bullet's caches and broadphase: rebuild the world and put its
            # other robots back where they were (finite ones; any others must be reset now)
            world.build()
            for local, body in enumerate(world.bodies):
                i = w * ROBOTS_PER_WORLD + local
                keep_q, keep_v = self.qpos[i], self.qvel[i]
                if i in index or not (np.isfinite(keep_q).all() and np.isfinite(keep_v).all()):
                    continue
                for j in (RAIL, HFE, KFE):
                    world.client.resetJointState(body, j, float(keep_q[j]), float(keep_v[j]))
        for row, i in enumerate(index):
            c, body = self.handle(int(i))
            for j in (RAIL, HFE, KFE):
                c.resetJointState(body, j, float(qpos[row][j]), float(qvel[row][j]))
        self._unstable[index] = False
        self._read()

    def track(
        self, desired: np.ndarray, substeps: int, push: np.ndarray | None = None
    ) -> np.ndarray:
        """The actuator law in numpy once per substep, applied with TORQUE_CONTROL; a push
        as an external force at the hip's centre of mass (Bullet clears it every step)."""
        torque_sum = np.zeros((self.num_robots, 2))
        for substep in range(substeps):
            target = desired[:, substep] if desired.ndim == 3 else desired
            torque = self.actuator(target, self.joint_pos, self.joint_vel) * self.strength
            torque_sum += torque
            rows = torque.tolist()
            for i, c, body in self._robots():
                c.setJointMotorControlArray(
                    body, (HFE, KFE), pybullet.TORQUE_CONTROL, forces=rows[i]
                )
                if push is not None and push[i] != 0.0:
                    centre = c.getLinkState(body, HIP_LINK, computeForwardKinematics=1)[0]
                    c.applyExternalForce(body, HIP_LINK, (0.0, 0.0, float(push[i])), centre,
                                         pybullet.WORLD_FRAME)  # fmt: skip
            for world in self._worlds:
                world.client.stepSimulation()
            self._read()
        return torque_sum / substeps

    def unstable(self) -> np.ndarray:
        return self._unstable.copy()

    def foot_state(self) -> tuple[np.ndarray, np.ndarray]:
        pos = np.zeros((self.num_robots, 3))
        vel = np.zeros((self.num_robots, 3))
        for i, c, body in self._robots():
            state = c.getLinkState(
                body, FOOT_LINK, computeLinkVelocity=1, computeForwardKinematics=1
            )
            com, frame_pos, frame_orn = np.array(state[0]), np.array(state[4]), state[5]
            rotation = np.array(c.getMatrixFromQuaternion(frame_orn)).reshape(3, 3)
            pos[i] = frame_pos + rotation @ np.array(robot.FOOT_CENTER)
            linear, angular = np.array(state[6]), np.array(state[7])
            vel[i] = linear + np.cross(angular, pos[i] - com)
        return pos, vel

    def contact(self) -> np.ndarray:
        for world in self._worlds:
            world.client.performCollisionDetection()
        touching = np.zeros(self.num_robots, dtype=bool)
        for i, c, body in self._robots():
            ground = self._worlds[i // ROBOTS_PER_WORLD].ground
            touching[i] = len(c.getContactPoints(body, ground, linkIndexA=FOOT_LINK)) > 0
        return touching

    def total_mass(self) -> float:
        c, body = self.handle(0)
        return float(sum(c.getDynamicsInfo(body, link)[0] for link in range(c.getNumJoints(body))))

    # -- rendering ---------------------------------------------------------------------------
    def render(self, index: int, width: int, height: int) -> np.ndarray:
        """Side view with PyBullet's TinyRenderer (CPU, no GL). Robots of one world share one
        spot: with several robots per world, all of them are in the picture."""
        c, _ = self.handle(index)
        view = c.computeViewMatrix(
            cameraEyePosition=[0.12, -1.5, 0.59], cameraTargetPosition=[0.12, 0.0, 0.38],
            cameraUpVector=[0.0, 0.0, 1.0],
        )  # fmt: skip
        projection = c.computeProjectionMatrixFOV(
            fov=45.0, aspect=width / height, nearVal=0.05, farVal=10.0
        )
        image = c.getCameraImage(
            width, height, view, projection, renderer=pybullet.ER_TINY_RENDERER
        )[2]
        return np.asarray(image, dtype=np.uint8).reshape(height, width, 4)[:, :, :3].copy()

    def close(self) -> None:
        for world in getattr(self, "_worlds", []):
            world.close()
        self._worlds = []
