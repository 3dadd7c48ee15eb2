"""MuJoCo backend: K hoppers as K rows of one state array, stepped by ``mujoco.rollout``.

One ``MjModel`` whose joints carry ``dcmotor`` actuators that are the actuator law of
:mod:`cpg_actor.robots.common.actuator` (PD, torque-speed line, torque limit; see
:func:`cpg_actor.robots.hopper.mjcf.actuator_xml`), their control being the desired joint
positions. A control step is ``mujoco.rollout`` with ``nstep`` = the substeps over chunks of
the K robots, on the calling thread and one helper thread per further core
(:class:`~cpg_actor.robots.common.threaded_rollout.ThreadedRollout`, GIL released), doing per
robot ``mj_setState`` -> desired positions into ``ctrl`` -> ``nstep`` x ``mj_step`` ->
``mj_getState``, with no Python between substeps. The state of all robots lives in one
contiguous numpy array. A single environment is the same code with K = 1 on the calling
thread, so the vector env and N single envs compute bit-identical trajectories.

The solver warm start (``qacc_warmstart``) is zero at the first substep of every control step
(``rollout`` does not return it) and carried between the substeps of one call. The constraint
solver converges to its tolerance either way, and a control step starts from nothing but the
returned state, so restoring that state is exact.
"""

from __future__ import annotations

import numpy as np

from cpg_actor.robots.common.actuator import Actuator
from cpg_actor.robots.common.backend import Backend
from cpg_actor.robots.common.mujoco_runtime import (
    CONTROL_SPEC,
    PUSH_SPEC,
    STATE_SPEC,
    TORQUE_SPEC,
    add_mass,
    default_threads,
    mujoco,
    offscreen_renderer,
)
from cpg_actor.robots.common.threaded_rollout import ThreadedRollout
from cpg_actor.robots.hopper.mjcf import MJCF_PATH, mjcf_text, set_foot_friction

CLOCK_START = 1000.0  # s, simulation time of every robot after a reset (see reset_robots)


def load_model(
    physics_dt: float, foot_friction: float, actuator: Actuator | None = None,
    payload: float = 0.0,
) -> mujoco.MjModel:  # fmt: skip
    """The hopper's MjModel with the configured actuators, timestep and foot-ground friction
    (the shipped MJCF, ``MJCF_PATH``, when ``actuator`` is None), ``payload`` kg on the hip."""
    if actuator is None:
        model = mujoco.MjModel.from_xml_path(str(MJCF_PATH))
    else:
        model = mujoco.MjModel.from_xml_string(mjcf_text(actuator))
    model.opt.timestep = physics_dt
    set_foot_friction(model, foot_friction)
    if payload:
        add_mass(model, "hip", payload)
    return model


class MujocoBackend(Backend):
    name = "mujoco"

    def __init__(
        self,
        actuator: Actuator,
        physics_dt: float,
        foot_friction: float,
        num_robots: int = 1,
        num_threads: int | None = None,
        payload: float = 0.0,
    ) -> None:
        self.model = load_model(physics_dt, foot_friction, actuator, payload)
        self.actuator = actuator
        self.strength = np.ones((int(num_robots), 1))  # per robot (randomised training)
        if actuator.law == "coast":  # the law in numpy, applied as joint torques: actuators off
            self.model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_ACTUATION.value
        self.num_robots = int(num_robots)
        per_thread = 16 if actuator.law == "coast" else 8
        self.num_threads = (
            default_threads(num_robots, per_thread) if num_threads is None else int(num_threads)
        )
        if self.num_threads < 1:
            raise ValueError(f"num_threads must be >= 1, got {num_threads}")
        self.num_threads = min(self.num_threads, self.num_robots)
        # the threads that step the robots, chunks taken in turn: a thread slowed by a busy
        # neighbour process hands work to others
        self.stepper = ThreadedRollout(self.model, self.num_robots, self.num_threads)
        self._data = mujoco.MjData(self.model)  # for the queries between control steps
        nq, nv = self.model.nq, self.model.nv
        self.nstate = mujoco.mj_stateSize(self.model, STATE_SPEC)
        self._state = np.zeros((self.num_robots, self.nstate))
        self._substeps = 0  # the buffers below are sized by track() for its substeps
        self.qpos = self._state[:, 1 : 1 + nq]
        self.qvel = self._state[:, 1 + nq : 1 + nq + nv]
        self._time = self._state[:, 0]
        self._foot_site = self.model.site("foot").id
        self._foot_geom = self.model.geom("foot").id
        self._hip = self.model.body("hip").id
        self._renderer: mujoco.Renderer | None = None
        self._camera: mujoco.MjvCamera | None = None

    def perturb_robots(self, index: np.ndarray, payload: np.ndarray, friction: np.ndarray,
                       strength: np.ndarray) -> None:  # fmt: skip
        """Each robot of ``index`` gets a model of its own (a payload, a friction, its
        actuators scaled by its strength; the coast law scales its torques instead)."""
        from cpg_actor.robots.common.perturbation import Perturbation

        coast = self.actuator.law == "coast"
        for row, i in enumerate(np.atleast_1d(index)):
            scaled = Perturbation(motor_strength=1.0 if coast else float(strength[row]))
            model = load_model(self.model.opt.timestep, float(friction[row]),
                               scaled.actuator(self.actuator), float(payload[row]))  # fmt: skip
            if coast:
                model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_ACTUATION.value
                self.strength[i] = strength[row]
            self.stepper.set_model(int(i), model)

    # -- state -----------------------------------------------------------------------------
    def reset_robots(self, index: np.ndarray, qpos: np.ndarray, qvel: np.ndarray) -> None:
        self._state[index] = 0.0
        # The clock starts at CLOCK_START, not 0: MuJoCo's reset-on-instability sets the time
        # to 0 (and qpos to qpos0) and carries on, so a clock behind CLOCK_START reveals it.
        self._time[index] = CLOCK_START
        self.qpos[index] = qpos
        self.qvel[index] = qvel

    def track(
        self, desired: np.ndarray, substeps: int, push: np.ndarray | None = None
    ) -> np.ndarray:
        if self.actuator.law == "coast":
            return self._track_per_substep(desired, substeps, push)
        if substeps != self._substeps:
            shape = (self.num_robots, substeps)
            self._control = np.zeros((*shape, self.model.nu))
            self._next = np.zeros((*shape, self.nstate))
            self._torque = np.zeros((*shape, self.model.nsensordata))  # actuatorfrc sensors
            self._substeps = substeps
        self._control[:] = desired if desired.ndim == 3 else desired[:, None, :]
        control, spec = self._control, CONTROL_SPEC
        if push is not None:  # the hip's applied force after the controls (mjSTATE_XFRC_APPLIED)
            control, spec = self._pushed(self._control, push), CONTROL_SPEC | PUSH_SPEC
        self.stepper.rollout(self._state, control, self._next, self._torque, spec, substeps)
        np.copyto(self._state, self._next[:, -1])
        return self._torque.sum(axis=1) / substeps

    def _pushed(self, control: np.ndarray, push: np.ndarray) -> np.ndarray:
        """``control`` (K, substeps, n) followed by every body's applied force and torque, the
        hip's vertical force ``push`` (K,) N."""
        forces = np.zeros((*control.shape[:2], self.model.nbody, 6))
        forces[:, :, self._hip, 2] = np.asarray(push, dtype=np.float64)[:, None]
        return np.ascontiguousarray(
            np.concatenate([control, forces.reshape(*control.shape[:2], -1)], axis=2)
        )

    def _track_per_substep(
        self, desired: np.ndarray, substeps: int, push: np.ndarray | None = None
    ) -> np.ndarray:
        """``actuator_law="coast"``: the law in numpy before every substep, one ``rollout``
        call per substep with the torques as ``qfrc_applied`` (the MuJoCo actuators are off)."""
        if getattr(self, "_torque_control", None) is None:
            self._torque_control = np.zeros((self.num_robots, 1, self.model.nv))
            self._one_step = np.zeros((self.num_robots, 1, self.nstate))
        torque_sum = np.zeros((self.num_robots, 2))
        for substep in range(substeps):
            target = desired[:, substep] if desired.ndim == 3 else desired
            # the law is homogeneous in the drive's strength: a robot's own scales its torque
            torque = self.actuator(target, self.joint_pos, self.joint_vel) * self.strength
            self._torque_control[:, 0, 1:3] = torque
            control, spec = self._torque_control, TORQUE_SPEC
            if push is not None:
                control, spec = self._pushed(control, push), TORQUE_SPEC | PUSH_SPEC
            self.stepper.rollout(self._state, control, self._one_step, None, spec, 1)
            np.copyto(self._state, self._one_step[:, 0])
            torque_sum += torque
        return torque_sum / substeps

    def get_state(self) -> np.ndarray:
        """The full physics state of every robot (``mjSTATE_FULLPHYSICS``: time, qpos, qvel,
        ...), ``(K, nstate)``. It is all a substep starts from (the solver's warm start is
        zero at every substep, see the module docstring), so restoring it is exact."""
        return self._state.copy()

    def set_state(self, state: np.ndarray) -> None:
        state = np.asarray(state, dtype=np.float64)
        if state.shape != self._state.shape:
            raise ValueError(
                f"a MuJoCo state must have shape {self._state.shape}, got {state.shape}"
            )
        np.copyto(self._state, state)

    def unstable(self) -> np.ndarray:
        # a robot MuJoCo reset since its last reset_robots has a clock restarted from 0
        return self._time < CLOCK_START

    def _load(self, index: int) -> mujoco.MjData:
        data, model = self._data, self.stepper.model_of(index)  # the robot's own model
        mujoco.mj_setState(model, data, self._state[index], STATE_SPEC)
        data.qfrc_applied[:] = 0.0
        mujoco.mj_forward(model, data)
        return data

    def foot_state(self) -> tuple[np.ndarray, np.ndarray]:
        pos = np.zeros((self.num_robots, 3))
        vel = np.zeros((self.num_robots, 3))
        velocity6 = np.zeros(6)
        for i in range(self.num_robots):
            data = self._load(i)
            pos[i] = data.site_xpos[self._foot_site]
            mujoco.mj_objectVelocity(
                self.model, data, mujoco.mjtObj.mjOBJ_SITE, self._foot_site, velocity6, 0
            )
            vel[i] = velocity6[3:]
        return pos, vel

    def contact(self) -> np.ndarray:
        touching = np.zeros(self.num_robots, dtype=bool)
        for i in range(self.num_robots):
            data = self._load(i)
            touching[i] = any(
                self._foot_geom in (c.geom1, c.geom2) for c in data.contact[: data.ncon]
            )
        return touching

    def total_mass(self) -> float:
        return float(self.model.body_mass[1:].sum())

    # -- rendering ---------------------------------------------------------------------------
    def render(self, index: int, width: int, height: int) -> np.ndarray:
        if self._renderer is None or (self._renderer.width, self._renderer.height) != (
            width,
            height,
        ):
            if self._renderer is not None:
                self._renderer.close()
                self._renderer = None
            self._renderer = offscreen_renderer(self.model, width, height)
            camera = mujoco.MjvCamera()
            camera.type = mujoco.mjtCamera.mjCAMERA_FREE
            camera.lookat[:] = (0.12, 0.0, 0.6)  # the rail up to a 0.6 m hop
            camera.distance = 2.3
            camera.azimuth = 90.0  # look along +y: the leg's sagittal plane, side view
            camera.elevation = -8.0
            self._camera = camera
        data = self._load(index)
        self._renderer.update_scene(data, camera=self._camera)
        return self._renderer.render().copy()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        if getattr(self, "stepper", None) is not None:
            self.stepper.close()
            self.stepper = None
