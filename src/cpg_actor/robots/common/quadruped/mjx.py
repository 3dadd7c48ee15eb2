"""The quadruped task on MuJoCo XLA (``sim="mjx"``): N quadrupeds stepped together by JAX on its
default device (a GPU where JAX has one), the task of :mod:`cpg_actor.tasks.velocity`. A
robot's MJX env is a subclass of :class:`MjxQuadrupedVectorEnv` naming its
:class:`~cpg_actor.robots.common.quadruped.model.QuadrupedModel` and its MuJoCo env.

The same robot, physics and task as
:class:`~cpg_actor.robots.common.quadruped.vector.QuadrupedVectorEnv` (MuJoCo on the CPU),
computed as pure jitted JAX functions, as the MJX hopper's
(:mod:`cpg_actor.robots.hopper.mjx.dynamics`):

* the robot's MJCF with plain ``motor`` actuators (MJX has no
  ``dcmotor``) whose torque is the actuator law of :mod:`cpg_actor.robots.common.actuator`,
  computed at
  every substep from the state; ``decimation`` substeps per control step (``lax.scan``); the
  Newton solver capped at ``mjx_iterations`` / ``mjx_ls_iterations``;
* MJX has no sensors here, so the env computes what the MuJoCo env's read, at the same
  instant (the start of the last substep, where ``mj_step`` evaluates sensors): the base's
  angular velocity (``qvel[3:6]``, the free joint's, in the base frame: the gyro), its linear
  velocity in the base frame (the velocimeter), the foot sites' positions (``framepos``). The
  base touching the ground (the MuJoCo env's ``touch`` sensor) is the lowest corner of the
  model's ``base_box`` at or below the ground;
* the observation, reward terms, falls, feet air time, episode metrics, SAME_STEP autoreset
  and ``info`` of the MuJoCo env; episode commands and reset noise from one JAX key per env
  (the same distributions, other numbers than the MuJoCo env for the same seed).

Float32, and MJX's solver is not MuJoCo's C one: trajectories agree within the tolerances of
``tests/robots/anymal/test_anymal_mjx.py`` (and the Go1's), not exactly.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np
import torch
from gymnasium.vector import AutoresetMode, VectorEnv

from cpg_actor.robots.common.actuator import Actuator
from cpg_actor.robots.common.checks import check_real_tensor, real_actions
from cpg_actor.robots.common.jax_bridge import reset_keys, to_host, torch_device
from cpg_actor.robots.common.mjx_runtime import load
from cpg_actor.robots.common.mujoco_runtime import mujoco
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.common.quadruped.model import QuadrupedModel
from cpg_actor.robots.common.quadruped.vector import (
    MIN_DISTANCE,
    QuadrupedVectorEnv,
    init_spaces,
    load_model,
    robot_spec,
)
from cpg_actor.robots.common.torch_env import EnvStep
from cpg_actor.tasks import velocity as task

jax, mjx = load()
jnp = jax.numpy

STATE_FIELDS = ("qpos", "qvel", "qacc_warmstart")  # what a step starts from (mjx.Data)
# the episode bookkeeping of the MuJoCo env (QuadrupedVectorEnv._EPISODE_FIELDS; it reads the
# feet's last positions from its sensors, this env keeps them in feet_xy) and the key
EPISODE_FIELDS = ("command", "last_action", "joint_vel_before", "elapsed", "air_time",
                  "in_contact", "speed_error_sum", "speed_sum", "work", "start_x",
                  "slip_sum", "planted_steps", "feet_xy", "key")  # fmt: skip
TRACE_INFO = ("reward_terms", "command", "contact", "base_height", "forward_speed",
              "desired_position", "measured_position")  # fmt: skip


def box_corners(box) -> np.ndarray:
    """The corners (8, 3) of a box (centre, half sizes) in the base frame: the base touches the
    ground when one does."""
    centre, half = (np.asarray(v) for v in box)
    return np.array([centre + half * np.array([sx, sy, sz])
                     for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])  # fmt: skip


class EnvState(NamedTuple):
    """Everything the next step depends on, N rows each (a JAX pytree)."""

    data: Any  # mjx.Data, batched
    command: Any  # (N, 3) forward, lateral, yaw command
    last_action: Any  # (N, 12) desired positions of the last step, rad
    joint_vel_before: Any  # (N, 12) joint velocities after the last step
    elapsed: Any  # (N,) int32 control steps of the episode
    air_time: Any  # (N, 4) s since each foot left the ground
    in_contact: Any  # (N, 4) bool
    speed_error_sum: Any  # (N,) sum of |forward speed - command|
    speed_sum: Any  # (N,) sum of the forward speed
    work: Any  # (N,) J, the joints' mechanical work (|torque x speed| dt)
    start_x: Any  # (N,) the base's x at the episode's start, m
    slip_sum: Any  # (N,) sum of the planted feet's sliding speeds, m/s
    planted_steps: Any  # (N,) int32 count of planted feet over the episode's steps
    feet_xy: Any  # (N, 4, 2) the feet's horizontal positions where the last step read them, m
    key: Any  # (N, 2) uint32 random key of each env


def mjx_model(quadruped: QuadrupedModel, config: QuadrupedConfig) -> mujoco.MjModel:
    """The quadruped's MjModel with torque-controlled motors, the configured timestep, friction
    and solver caps."""
    model = load_model(quadruped, config, torque_control=True)
    model.opt.iterations = config.mjx_iterations
    model.opt.ls_iterations = config.mjx_ls_iterations
    return model


class QuadrupedDynamics:
    """Jitted ``reset(keys)`` and ``step(state, actions)`` for one robot and config."""

    def __init__(self, quadruped: QuadrupedModel, config: QuadrupedConfig) -> None:
        self.quadruped = quadruped
        self.config = config.validate()
        self.actuator = Actuator.from_config(config)
        self.mj_model = mjx_model(quadruped, config)
        self.model = mjx.put_model(self.mj_model)
        self._empty = mjx.make_data(self.model)
        self._feet = jnp.asarray([self.mj_model.site(f"{leg}_foot").id for leg in quadruped.legs])
        self._base = self.mj_model.body(quadruped.base_body).id
        self._corners = jnp.asarray(box_corners(quadruped.base_box), dtype=jnp.float32)
        self._nominal = jnp.asarray(quadruped.nominal_pose, dtype=jnp.float32)
        self._low = jnp.asarray(quadruped.low, dtype=jnp.float32)
        self._high = jnp.asarray(quadruped.high, dtype=jnp.float32)
        self.reset = jax.jit(self._reset)
        self.step = jax.jit(self._step)

    # -- one robot ------------------------------------------------------------------------------
    def _fresh(self, key):
        """A new episode's pose (nominal plus noise, feet on the ground, at rest), command and
        feet positions (4, 2) for one robot, and its key advanced."""
        key, noise_key, command_key = jax.random.split(key, 3)
        cfg = self.config
        noise = jax.random.uniform(noise_key, (12,), minval=-cfg.reset_noise,
                                   maxval=cfg.reset_noise)  # fmt: skip
        joints = jnp.clip(self._nominal + noise, self._low, self._high)
        low, high = cfg.command_range
        speed = jax.random.uniform(command_key, (), minval=low, maxval=high)
        # the lateral and yaw commands from keys folded out of the forward one's (the forward
        # task's draws unchanged)
        lateral, yaw = (
            jax.random.uniform(jax.random.fold_in(command_key, column), (),
                               minval=getattr(cfg, name)[0], maxval=getattr(cfg, name)[1])
            for column, name in ((1, "lateral_range"), (2, "yaw_range"))
        )  # fmt: skip
        qpos = self._empty.qpos.at[7:].set(joints)
        placed = mjx.kinematics(self.model, self._empty.replace(qpos=qpos))
        lowest = placed.site_xpos[self._feet, 2].min()
        qpos = qpos.at[2].add(self.quadruped.foot_radius - lowest)  # feet on the ground
        command = jnp.stack([speed, lateral, yaw]).astype(jnp.float32)
        feet_xy = placed.site_xpos[self._feet, :2]  # the lift above moves no foot sideways
        return self._empty.replace(qpos=qpos), command, joints, feet_xy, key

    def control(self, data, desired):
        """``decimation`` substeps of one robot: the actuator law, then ``mjx.step``. Returns
        the data after them, the data the last substep started from (the instant the MuJoCo
        env's sensors read), the last substep's torque and the joints' work (J)."""
        dt = self.config.physics_dt

        def substep(carry, _):
            data, _, _, work = carry
            torque = self.actuator(desired, data.qpos[7:], data.qvel[6:])
            after = mjx.step(self.model, data.replace(ctrl=torque))
            work = work + jnp.abs(torque * after.qvel[6:]).sum() * dt
            return (after, data, torque, work), None

        start = (data, data, jnp.zeros(12, dtype=desired.dtype), jnp.zeros((), desired.dtype))
        with jax.default_matmul_precision("float32"):  # no TensorFloat32 on NVIDIA GPUs
            (data, before, torque, work), _ = jax.lax.scan(
                substep, start, None, length=self.config.decimation
            )
        # the positions MuJoCo evaluates inside the last step (before it integrates)
        before = mjx.kinematics(self.model, before)
        return data, before, torque, work

    # -- the batch ------------------------------------------------------------------------------
    def _observe(self, data, gyro, command, last_action):
        gravity = task.projected_gravity(data.qpos[:, 3:7])
        obs = task.observation(gyro, gravity, command, data.qpos[:, 7:], data.qvel[:, 6:],
                               last_action, self._nominal)  # fmt: skip
        return jnp.nan_to_num(obs, nan=0.0, posinf=0.0, neginf=0.0)

    def _reset(self, keys):
        """New episodes for all N robots (``keys``: (N, 2) uint32): ``(state, obs)``."""
        data, command, joints, feet_xy, keys = jax.vmap(self._fresh)(keys)
        n = keys.shape[0]
        zeros = jnp.zeros(n, dtype=jnp.float32)
        state = EnvState(
            data=data, command=command, last_action=joints,
            joint_vel_before=jnp.zeros((n, 12), jnp.float32),
            elapsed=jnp.zeros(n, jnp.int32), air_time=jnp.zeros((n, 4), jnp.float32),
            in_contact=jnp.ones((n, 4), bool), speed_error_sum=zeros, speed_sum=zeros,
            work=zeros, start_x=data.qpos[:, 0], slip_sum=zeros,
            planted_steps=jnp.zeros(n, jnp.int32), feet_xy=feet_xy, key=keys,
        )  # fmt: skip
        return state, self._observe(data, data.qvel[:, 3:6], command, joints)

    def _step(self, state: EnvState, actions):
        """One control step of all N robots: ``(state, outputs)`` (module docstring)."""
        cfg, dt = self.config, self.config.control_dt
        actions = actions.astype(jnp.float32)
        if cfg.normalized_actions:
            actions = (
                self._low + (jnp.clip(actions, -1.0, 1.0) + 1.0) * (self._high - self._low) / 2.0
            )
        desired = jnp.clip(actions, self._low, self._high)
        data, before, torque, work = jax.vmap(self.control)(state.data, desired)
        qpos, qvel = data.qpos, data.qvel
        elapsed = state.elapsed + 1

        # the MuJoCo env's sensors: the start of the last substep
        rotation = before.xmat[:, self._base]  # (N, 3, 3) base to world
        lin_vel = jnp.einsum("nji,nj->ni", rotation, before.qvel[:, 0:3])
        ang_vel = before.qvel[:, 3:6]
        feet = before.site_xpos[:, self._feet]
        corners = before.xpos[:, self._base, None, :] + jnp.einsum(
            "nij,kj->nki", rotation, self._corners
        )
        base_touch = corners[:, :, 2].min(axis=1) <= 0.0

        gravity = task.projected_gravity(qpos[:, 3:7])
        height = qpos[:, 2]
        joint_vel = qvel[:, 6:]
        joint_acc = (joint_vel - state.joint_vel_before) / dt
        contact = feet[:, :, 2] < self.quadruped.foot_radius + 0.005
        slip, planted = task.planted_slip(feet[:, :, :2], state.feet_xy, contact,
                                          state.in_contact, dt)  # fmt: skip
        slip_sum = state.slip_sum + slip.sum(axis=1)
        planted_steps = state.planted_steps + planted.sum(axis=1)
        touchdown = contact & ~state.in_contact
        air_time = state.air_time + dt
        moving = jnp.linalg.norm(state.command[:, :2], axis=1) > 0.1
        air_paid = jnp.sum((air_time - 0.5) * touchdown, axis=1) * moving
        air_time = jnp.where(contact, 0.0, air_time)
        terms = task.reward_terms(
            lin_vel, ang_vel, gravity, height, state.command, torque, joint_acc, desired,
            state.last_action, air_paid, slip, cfg.tracking_sigma, cfg.base_height_target,
        )  # fmt: skip
        scaled = {name: value * cfg.reward_scales[name] * dt for name, value in terms.items()}
        unstable = ~(jnp.isfinite(qpos).all(axis=1) & jnp.isfinite(qvel).all(axis=1))
        scaled = {name: jnp.where(unstable, 0.0, value) for name, value in scaled.items()}
        reward = sum(scaled.values())
        speed_error_sum = state.speed_error_sum + jnp.abs(lin_vel[:, 0] - state.command[:, 0])
        speed_sum = state.speed_sum + lin_vel[:, 0]
        work = state.work + work

        terminated = (task.fallen(height, gravity, cfg.fall_height, cfg.fall_tilt)
                      | base_touch | unstable)  # fmt: skip
        truncated = (elapsed >= cfg.episode_steps) & ~terminated
        done = terminated | truncated
        obs = jnp.where(unstable[:, None], 0.0, self._observe(data, ang_vel, state.command,
                                                              desired))  # fmt: skip
        steps = elapsed.astype(jnp.float32)
        distance = qpos[:, 0] - state.start_x
        weight = self.quadruped.total_mass * self.quadruped.gravity
        nan = jnp.full_like(steps, jnp.nan)
        metrics = {
            "speed_error": speed_error_sum / steps,
            "forward_speed": speed_sum / steps,
            "fell": terminated.astype(jnp.float32),
            "episode_seconds": steps * dt,
            "cost_of_transport": jnp.where(
                distance >= MIN_DISTANCE, work / (weight * distance), nan
            ),  # fmt: skip
            "foot_slip": jnp.where(
                planted_steps > 0, slip_sum / jnp.maximum(planted_steps, 1), nan
            ),
        }
        metrics = {name: jnp.where(done, value, nan) for name, value in metrics.items()}

        # autoreset (SAME_STEP): the envs that ended start their next episode now
        fresh, command, joints, fresh_feet_xy, keys = jax.vmap(self._fresh)(state.key)

        def pick(new, old):
            return jnp.where(done.reshape((-1,) + (1,) * (old.ndim - 1)), new, old)

        data = data.replace(**{name: pick(getattr(fresh, name), getattr(data, name))
                               for name in STATE_FIELDS})  # fmt: skip
        zero = jnp.zeros_like(speed_sum)
        next_state = EnvState(
            data=data, command=pick(command, state.command),
            last_action=pick(joints, desired),
            joint_vel_before=pick(jnp.zeros_like(joint_vel), joint_vel),
            elapsed=jnp.where(done, 0, elapsed), air_time=pick(jnp.zeros_like(air_time), air_time),
            in_contact=pick(jnp.ones_like(contact), contact),
            speed_error_sum=pick(zero, speed_error_sum), speed_sum=pick(zero, speed_sum),
            work=pick(zero, work), start_x=pick(fresh.qpos[:, 0], state.start_x),
            slip_sum=pick(zero, slip_sum),
            planted_steps=pick(jnp.zeros_like(planted_steps), planted_steps),
            feet_xy=pick(fresh_feet_xy, feet[:, :, :2]), key=pick(keys, state.key),
        )  # fmt: skip
        # a fresh robot is at rest: its gyro reads 0
        gyro = pick(jnp.zeros_like(ang_vel), ang_vel)
        next_obs = self._observe(data, gyro, next_state.command, next_state.last_action)
        next_obs = jnp.where((unstable & ~done)[:, None], 0.0, next_obs)
        outputs = {
            "obs": next_obs, "reward": reward, "terminated": terminated, "truncated": truncated,
            "final_obs": obs, "episode_metrics": metrics, "reward_terms": scaled,
            "command": state.command, "contact": contact, "base_height": height,
            "forward_speed": lin_vel[:, 0], "desired_position": desired,
            "measured_position": qpos[:, 7:],
        }  # fmt: skip
        return next_state, outputs


_DYNAMICS: dict[tuple, QuadrupedDynamics] = {}


def dynamics_for(quadruped: QuadrupedModel, config: QuadrupedConfig) -> QuadrupedDynamics:
    """One :class:`QuadrupedDynamics` per robot, config and process (its jitted functions
    shared): a range read from YAML or ``--set`` (a list) is the same config as the default's
    tuple."""
    key = quadruped.name + repr(
        sorted((k, tuple(v) if isinstance(v, list) else v) for k, v in vars(config).items())
    )
    if key not in _DYNAMICS:
        _DYNAMICS[key] = QuadrupedDynamics(quadruped, config)
    return _DYNAMICS[key]


class MjxQuadrupedVectorEnv(VectorEnv):
    """N quadrupeds on MJX: the Gymnasium face of the robot's MuJoCo env (``mujoco_env``, a
    :class:`~cpg_actor.robots.common.quadruped.vector.QuadrupedVectorEnv`; numpy, copied to the
    host) and the trainer's tensor face (``reset_tensors`` / ``step_tensors``: torch through
    DLPack on JAX's device), as the MJX hopper's. ``num_threads`` is accepted and ignored;
    ``max_episode_steps`` is checked as the MuJoCo env's. A robot's subclass sets
    ``mujoco_env``; the robot is its ``quadruped``."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}
    mujoco_env: type[QuadrupedVectorEnv]  # the robot's MuJoCo env (a subclass sets it)

    @property
    def quadruped(self) -> QuadrupedModel:
        return self.mujoco_env.quadruped

    @property
    def foot_names(self) -> tuple[str, ...]:
        """The columns of ``info["contact"]``."""
        return self.quadruped.legs

    def __init__(
        self,
        num_envs: int,
        config: QuadrupedConfig | dict | None = None,
        num_threads: int | None = None,
        max_episode_steps: int | None = None,
    ) -> None:
        init_spaces(self, num_envs, config, max_episode_steps)
        if self.config.sim != "mjx":
            raise ValueError(
                f"{type(self).__name__} simulates with MJX, got sim={self.config.sim!r}"
            )
        self.robot = robot_spec(self.quadruped, self.config)
        self.dynamics = dynamics_for(self.quadruped, self.config)
        self.jax_device = jax.devices()[0]
        self.device = torch_device(self.jax_device)
        self.num_threads = None
        self._state: EnvState | None = None
        self._renderer = None
        self._closed = False

    def _check_started(self, what: str) -> None:
        if self._closed:
            raise gym.error.ClosedEnvironmentError(f"{what}() on a closed environment")
        if self._state is None and what != "reset":
            raise RuntimeError(f"call reset() before {what}()")

    @property
    def jax_state(self) -> EnvState | None:
        """Every env's state as the dynamics step takes it; None before the first reset."""
        return self._state

    # -- the tensor face ----------------------------------------------------------------------
    def reset_tensors(self, seed: int | list[int] | None = None) -> tuple[torch.Tensor, dict]:
        self._check_started("reset")
        keys = reset_keys(seed, self.num_envs, self.jax_device)
        self._state, obs = self.dynamics.reset(keys)
        return torch.from_dlpack(obs), {"command": torch.from_dlpack(self._state.command)}

    def step_tensors(self, actions: torch.Tensor, check_finite: bool = True) -> EnvStep:
        """One control step from desired joint positions ``(N, 12)`` (a tensor on any device);
        ``check_finite`` as the MJX hopper's (False: no wait for the device)."""
        self._check_started("step")
        if tuple(actions.shape) != (self.num_envs, 12):
            raise ValueError(f"actions must have shape {(self.num_envs, 12)} (desired joint "
                             f"positions, rad, joints {self.quadruped.joint_names}), got "
                             f"{tuple(actions.shape)}")  # fmt: skip
        check_real_tensor(actions)
        if check_finite and not bool(torch.isfinite(actions).all()):
            raise ValueError("actions must be finite, got NaN or inf")
        if actions.device != self.device:
            actions = actions.to(self.device)
        return self._advance(
            jax.dlpack.from_dlpack(actions.detach().to(torch.float32).contiguous())
        )

    def _advance(self, actions) -> EnvStep:
        self._state, out = self.dynamics.step(self._state, actions)
        tensors = jax.tree.map(torch.from_dlpack, out)
        done = tensors["terminated"] | tensors["truncated"]
        info = {key: tensors[key] for key in TRACE_INFO}
        info.update(final_obs=tensors["final_obs"], _final_obs=done,
                    episode_metrics=tensors["episode_metrics"])  # fmt: skip
        return EnvStep(
            obs=tensors["obs"], reward=tensors["reward"], terminated=tensors["terminated"],
            truncated=tensors["truncated"], final_obs=tensors["final_obs"],
            episode_metrics=tensors["episode_metrics"], reward_terms=tensors["reward_terms"],
            info=info,
        )  # fmt: skip

    # -- the Gymnasium face -------------------------------------------------------------------
    def reset(
        self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every env. ``seed``: an int s (env i gets s + i), a list of N ints, or None."""
        obs, info = self.reset_tensors(seed)
        return to_host(obs), to_host(info)

    def step(self, actions: Any):
        self._check_started("step")
        actions = real_actions(actions, f"of shape {(self.num_envs, 12)}", np.float32)
        if actions.shape != (self.num_envs, 12):
            raise ValueError(f"actions must have shape {(self.num_envs, 12)} (desired joint "
                             f"positions, rad, joints {self.quadruped.joint_names}), got "
                             f"{actions.shape}")  # fmt: skip
        if not np.isfinite(actions).all():
            raise ValueError("actions must be finite, got NaN or inf")
        out = self._advance(jax.device_put(actions, self.jax_device))
        info = to_host(out.info)
        info["episode_metrics"] = {k: v.astype(np.float64) for k, v in
                                   info["episode_metrics"].items()}  # fmt: skip
        return (to_host(out.obs), to_host(out.reward).astype(np.float64), to_host(out.terminated),
                to_host(out.truncated), info)  # fmt: skip

    # -- checkpoints --------------------------------------------------------------------------
    def get_state(self) -> dict[str, Any]:
        """Everything the next step depends on, as CPU tensors: each robot's ``qpos``, ``qvel``
        and solver warm start, the episode bookkeeping and each env's random key;
        :meth:`set_state` continues exactly."""
        self._check_started("get_state")
        state = self._state
        fields = {name: getattr(state.data, name) for name in STATE_FIELDS}
        fields.update({name: getattr(state, name) for name in EPISODE_FIELDS})
        key = "mjx-" + self.quadruped.state_key
        return {key: {k: torch.from_numpy(np.array(v)) for k, v in fields.items()}}

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`get_state` returned (ValueError if it does not fit)."""
        if self._closed:
            raise gym.error.ClosedEnvironmentError("set_state() on a closed environment")
        key = "mjx-" + self.quadruped.state_key
        if not isinstance(state, dict) or key not in state:
            raise ValueError(f"not a state of {type(self).__name__} (get_state() makes one)")
        fields = {k: np.asarray(v.numpy()) for k, v in state[key].items()}
        missing = [k for k in (*STATE_FIELDS, *EPISODE_FIELDS) if k not in fields]
        if missing:
            raise ValueError(f"the MJX state lacks {', '.join(missing)}")
        if fields["qpos"].shape[0] != self.num_envs:
            raise ValueError(f"the state has {fields['qpos'].shape[0]} envs, this env "
                             f"{self.num_envs}")  # fmt: skip
        if self._state is None:
            self.reset_tensors(seed=0)
        put = lambda name: jax.device_put(fields[name], self.jax_device)  # noqa: E731
        data = self._state.data.replace(**{name: put(name) for name in STATE_FIELDS})
        self._state = EnvState(data=data, **{name: put(name) for name in EPISODE_FIELDS})

    # -- rendering ----------------------------------------------------------------------------
    def render_frame(self, index: int = 0) -> np.ndarray:
        """An RGB frame of env ``index``, drawn by MuJoCo on the CPU from that robot's state
        (the MuJoCo env's camera and scene; needs an OpenGL backend)."""
        self._check_started("render_frame")
        if not 0 <= index < self.num_envs:
            raise ValueError(f"index must be in 0..{self.num_envs - 1}, got {index}")
        if self._renderer is None:
            self._renderer = self.mujoco_env(1, self.config.replace(sim="mujoco"), 1)
            self._renderer.reset(seed=0)
        data = self._state.data
        return self._renderer.render_pose(np.asarray(data.qpos[index], dtype=np.float64))

    def close_extras(self, **kwargs: Any) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        self._state = None
        self._closed = True
