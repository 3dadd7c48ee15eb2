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
* the task's step of the MuJoCo env, the same function (:func:`cpg_actor.tasks.velocity.step`:
  observation, reward terms, falls, feet air time, episode metrics, ``info``) on JAX arrays;
  SAME_STEP autoreset; episode commands and reset noise from one JAX key per env (the same
  distributions, other numbers than the MuJoCo env for the same seed).

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
# what a saved state holds beside STATE_FIELDS: the task's episode and each env's key
EPISODE_FIELDS = (*task.Episode._fields, "key")


def box_corners(box) -> np.ndarray:
    """The corners (8, 3) of a box (centre, half sizes) in the base frame: the base touches the
    ground when one does."""
    centre, half = (np.asarray(v) for v in box)
    return np.array([centre + half * np.array([sx, sy, sz])
                     for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])  # fmt: skip


class EnvState(NamedTuple):
    """Everything the next step depends on, N rows each (a JAX pytree)."""

    data: Any  # mjx.Data, batched
    episode: task.Episode  # the task's bookkeeping
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

    def reading(self, data, before, torque, work):
        """What the task reads after a step (:class:`cpg_actor.tasks.velocity.Reading`): the
        MuJoCo env's sensors at the start of the last substep (``before``)."""
        rotation = before.xmat[:, self._base]  # (N, 3, 3) base to world
        corners = before.xpos[:, self._base, None, :] + jnp.einsum(
            "nij,kj->nki", rotation, self._corners
        )
        return task.Reading(
            qpos=data.qpos, qvel=data.qvel,
            lin_vel=jnp.einsum("nji,nj->ni", rotation, before.qvel[:, 0:3]),
            ang_vel=before.qvel[:, 3:6], feet=before.site_xpos[:, self._feet], torque=torque,
            work=work, base_touch=corners[:, :, 2].min(axis=1) <= 0.0,
            unstable=~(jnp.isfinite(data.qpos).all(axis=1) & jnp.isfinite(data.qvel).all(axis=1)),
        )  # fmt: skip

    # -- the batch ------------------------------------------------------------------------------
    def _starts(self, keys):
        """New episodes for N robots: their data, the task's episodes and the keys advanced."""
        data, command, joints, feet_xy, keys = jax.vmap(self._fresh)(keys)
        return data, task.new_episode(command, joints, data.qpos[:, 0], feet_xy), keys

    def _reset(self, keys, episode=None):
        """New episodes for all N robots (``keys``: (N, 2) uint32): ``(state, obs, info)``."""
        data, started, keys = self._starts(keys)
        obs = task.observe(data.qpos, data.qvel, data.qvel[:, 3:6], started.command,
                           started.last_action, self._nominal)  # fmt: skip
        return EnvState(data, started, keys), obs, {"command": started.command}

    def _step(self, state: EnvState, actions, episode=None):
        """One control step of all N robots: ``(state, outputs)`` (module docstring)."""
        cfg = self.config
        desired = task.desired_positions(actions.astype(jnp.float32), self._low, self._high,
                                         cfg.normalized_actions)  # fmt: skip
        data, before, torque, work = jax.vmap(self.control)(state.data, desired)
        robot = self.quadruped
        reading = self.reading(data, before, torque, work)
        after, out = task.step(cfg, state.episode, reading, desired, self._nominal,
                               robot.foot_radius, robot.total_mass * robot.gravity)  # fmt: skip
        done = out["terminated"] | out["truncated"]

        # autoreset (SAME_STEP): the envs that ended start their next episode now
        fresh, started, keys = self._starts(state.key)
        data = data.replace(**{name: task.rows(done, getattr(fresh, name), getattr(data, name))
                               for name in STATE_FIELDS})  # fmt: skip
        after = task.restart(after, done, started)
        gyro = task.rows(done, jnp.zeros_like(before.qvel[:, 3:6]), before.qvel[:, 3:6])
        fresh_obs = task.observe(data.qpos, data.qvel, gyro, after.command, after.last_action,
                                 self._nominal)  # fmt: skip
        outputs = {
            "obs": task.rows(done, fresh_obs, out["obs"]), "reward": out["reward"],
            "terminated": out["terminated"], "truncated": out["truncated"],
            "final_obs": out["obs"], "episode_metrics": out["episode_metrics"],
            "info": {"reward_terms": out["reward_terms"], **out["info"]},
        }  # fmt: skip
        return EnvState(data, after, task.rows(done, keys, state.key)), outputs


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
        self._state, obs, info = self.dynamics.reset(keys)
        return torch.from_dlpack(obs), jax.tree.map(torch.from_dlpack, info)

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
        info = dict(tensors["info"])
        info.update(final_obs=tensors["final_obs"], _final_obs=done,
                    episode_metrics=tensors["episode_metrics"])  # fmt: skip
        return EnvStep(
            obs=tensors["obs"], reward=tensors["reward"], terminated=tensors["terminated"],
            truncated=tensors["truncated"], final_obs=tensors["final_obs"],
            episode_metrics=tensors["episode_metrics"], reward_terms=info["reward_terms"],
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
        fields.update(state.episode._asdict(), key=state.key)
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
        episode = task.Episode(*(put(name) for name in task.Episode._fields))
        self._state = EnvState(data, episode, put("key"))

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
