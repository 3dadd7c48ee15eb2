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
  SAME_STEP autoreset; episode commands (drawn again every ``command_resample_seconds``
  where that is not 0) and reset noise from one JAX key per env (the same distributions,
  other numbers than the MuJoCo env for the same seed);
* on rough ground (``config.terrain``, with the feet alone on the ground: MJX collides no
  height field with cylinders), the MuJoCo env's tiles, heights over the ground and
  curriculum as JAX functions (:mod:`cpg_actor.robots.common.quadruped.mjx_ground`).

Float32, and MJX's solver is not MuJoCo's C one: trajectories agree within the tolerances of
``tests/robots/anymal/test_anymal_mjx.py`` (and the Go1's), not exactly.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from cpg_actor.robots.common.actuator import Actuator
from cpg_actor.robots.common.mjx_runtime import STATE_FIELDS, check_impl, load
from cpg_actor.robots.common.mjx_vector import MjxVectorEnv
from cpg_actor.robots.common.mujoco_runtime import mujoco
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.common.quadruped.mjx_ground import GroundState, MjxGround
from cpg_actor.robots.common.quadruped.model import QuadrupedModel
from cpg_actor.robots.common.quadruped.vector import (
    ADDED_FIELDS,
    QuadrupedVectorEnv,
    init_spaces,
    load_model,
)
from cpg_actor.tasks import velocity as task

jax, mjx = load()
jnp = jax.numpy


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
    ground: Any = None  # each env's GroundState on rough ground (None: flat)


def mjx_model(quadruped: QuadrupedModel, config: QuadrupedConfig) -> mujoco.MjModel:
    """The quadruped's MjModel with torque-controlled motors, the configured timestep, friction
    and solver caps."""
    model = load_model(quadruped, config, torque_control=True)
    model.opt.iterations = config.mjx_iterations
    model.opt.ls_iterations = config.mjx_ls_iterations
    return model


class QuadrupedDynamics:
    """Jitted ``reset(keys, episode)`` and ``step(state, actions, episode)`` for one robot and
    config (``episode`` unused: every config number is compiled in)."""

    def __init__(self, quadruped: QuadrupedModel, config: QuadrupedConfig) -> None:
        self.quadruped = quadruped
        self.config = config.validate()
        self.actuator = Actuator.from_config(config)
        check_impl(config.mjx_impl)
        self.mj_model = mjx_model(quadruped, config)
        self.model = mjx.put_model(self.mj_model, impl=config.mjx_impl)
        self._empty = mjx.make_data(self.mj_model, impl=config.mjx_impl)
        self._feet = jnp.asarray([self.mj_model.site(f"{leg}_foot").id for leg in quadruped.legs])
        self._base = self.mj_model.body(quadruped.base_body).id
        self._corners = jnp.asarray(box_corners(quadruped.base_box), dtype=jnp.float32)
        self._nominal = jnp.asarray(quadruped.nominal_pose, dtype=jnp.float32)
        self._low = jnp.asarray(quadruped.low, dtype=jnp.float32)
        self._high = jnp.asarray(quadruped.high, dtype=jnp.float32)
        self.ground = None  # rough ground (mjx_ground; None: flat)
        if config.terrain.active:
            self.ground = MjxGround(config.terrain, config.episode_seconds)
        self.reset = jax.jit(self._reset)
        self.step = jax.jit(self._step)

    # -- one robot ------------------------------------------------------------------------------
    def _fresh(self, key, level=None, column=None):
        """A new episode's pose (nominal plus noise, feet on the ground, at rest), command and
        feet positions (4, 2) for one robot, and its key advanced."""
        key, noise_key, command_key = jax.random.split(key, 3)
        cfg = self.config
        noise = jax.random.uniform(noise_key, (12,), minval=-cfg.reset_noise,
                                   maxval=cfg.reset_noise)  # fmt: skip
        joints = jnp.clip(self._nominal + noise, self._low, self._high)
        qpos = self._empty.qpos.at[7:].set(joints)
        if self.ground is not None:  # on the tile of its ``level`` and kind ``column``
            qpos, placed = self.ground.place(self.model, self._empty.replace(qpos=qpos),
                                             noise_key, level, column, self._feet,
                                             self.quadruped.foot_radius)  # fmt: skip
        else:
            placed = mjx.kinematics(self.model, self._empty.replace(qpos=qpos))
            lowest = placed.site_xpos[self._feet, 2].min()
            qpos = qpos.at[2].add(self.quadruped.foot_radius - lowest)  # feet on the ground
        command = self.command(command_key)
        feet_xy = placed.site_xpos[self._feet, :2]  # the lift above moves no foot sideways
        return self._empty.replace(qpos=qpos), command, joints, feet_xy, key

    def command(self, key):
        """One robot's command (3,) from ``key``: each entry uniform in its range, all zero
        with probability ``standing_share`` (the MuJoCo env's distribution)."""
        cfg = self.config
        low, high = cfg.command_range
        speed = jax.random.uniform(key, (), minval=low, maxval=high)
        # the lateral and yaw commands from keys folded out of the forward one's (the forward
        # task's draws unchanged)
        lateral, yaw = (
            jax.random.uniform(jax.random.fold_in(key, column), (),
                               minval=getattr(cfg, name)[0], maxval=getattr(cfg, name)[1])
            for column, name in ((1, "lateral_range"), (2, "yaw_range"))
        )  # fmt: skip
        command = jnp.stack([speed, lateral, yaw]).astype(jnp.float32)
        if cfg.standing_share > 0:
            standing = jax.random.uniform(jax.random.fold_in(key, 3), ()) < cfg.standing_share
            command = jnp.where(standing, jnp.zeros_like(command), command)
        return command

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
        reading = task.Reading(
            qpos=data.qpos, qvel=data.qvel,
            lin_vel=jnp.einsum("nji,nj->ni", rotation, before.qvel[:, 0:3]),
            ang_vel=before.qvel[:, 3:6], feet=before.site_xpos[:, self._feet], torque=torque,
            work=work, base_touch=corners[:, :, 2].min(axis=1) <= 0.0,
            unstable=~(jnp.isfinite(data.qpos).all(axis=1) & jnp.isfinite(data.qvel).all(axis=1)),
        )  # fmt: skip
        if self.ground is not None:  # heights over the ground under the robot
            reading = self.ground.relative(reading, corners)
        return reading

    # -- the batch ------------------------------------------------------------------------------
    def _starts(self, keys, levels=None):
        """New episodes for N robots: their data, the task's episodes and the keys advanced
        (on rough ground on the tiles of their ``levels``)."""
        if self.ground is None:
            data, command, joints, feet_xy, keys = jax.vmap(self._fresh)(keys)
        else:
            columns = self.ground.columns(keys.shape[0])
            data, command, joints, feet_xy, keys = jax.vmap(self._fresh)(keys, levels, columns)
        return data, task.new_episode(command, joints, data.qpos[:, 0], feet_xy), keys

    def _reset(self, keys, episode=None):
        """New episodes for all N robots (``keys``: (N, 2) uint32): ``(state, obs, info)``."""
        levels = None if self.ground is None else self.ground.first_levels(keys.shape[0])
        data, started, keys = self._starts(keys, levels)
        obs = task.observe(data.qpos, data.qvel, data.qvel[:, 3:6], started.command,
                           started.last_action, self._nominal)  # fmt: skip
        ground = None if levels is None else GroundState(levels, data.qpos[:, :2])
        return EnvState(data, started, keys, ground), obs, {"command": started.command}

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
        if cfg.resample_steps:  # a new command where one is due (the next step runs under it)
            due = (after.elapsed % cfg.resample_steps == 0) & ~done
            # its key folded out of the env's by the step count: the env's key stream as it was
            command = jax.vmap(lambda key, n: self.command(jax.random.fold_in(key, n)))(
                state.key, after.elapsed
            )
            after, out["obs"] = task.resample(after, out["obs"], command, due)

        levels = None
        if self.ground is not None:  # the curriculum, before the next episodes start
            levels, out["episode_metrics"]["terrain_level"] = self.ground.end_episodes(
                state.ground, done, data.qpos, out["info"]["command"], state.key)  # fmt: skip

        # autoreset (SAME_STEP): the envs that ended start their next episode now
        fresh, started, keys = self._starts(state.key, levels)
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
        ground = None
        if self.ground is not None:
            ground = GroundState(levels, task.rows(done, data.qpos[:, :2], state.ground.start_xy))
        return EnvState(data, after, task.rows(done, keys, state.key), ground), outputs


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


class MjxQuadrupedVectorEnv(MjxVectorEnv):
    """N quadrupeds on MJX behind the faces of every MJX env
    (:class:`~cpg_actor.robots.common.mjx_vector.MjxVectorEnv`), with the info and episode
    metrics of the robot's MuJoCo env (``mujoco_env``, a
    :class:`~cpg_actor.robots.common.quadruped.vector.QuadrupedVectorEnv`). ``num_threads`` is
    accepted and ignored; ``max_episode_steps`` is checked as the MuJoCo env's. A robot's
    subclass sets ``mujoco_env``; the robot is its ``quadruped``."""

    mujoco_env: type[QuadrupedVectorEnv]  # the robot's MuJoCo env (a subclass sets it)
    saved_fields = (*task.Episode._fields, "key")
    added_fields = ADDED_FIELDS  # zero in states saved before them

    @property
    def quadruped(self) -> QuadrupedModel:
        return self.mujoco_env.quadruped

    @property
    def foot_names(self) -> tuple[str, ...]:
        """The columns of ``info["contact"]``."""
        return self.quadruped.legs

    @property
    def state_key(self) -> str:
        return "mjx-" + self.quadruped.state_key

    @property
    def action_hint(self) -> str:
        return f"desired joint positions, rad, joints {self.quadruped.joint_names}"

    def __init__(
        self,
        num_envs: int,
        config: QuadrupedConfig | dict | None = None,
        num_threads: int | None = None,
        max_episode_steps: int | None = None,
    ) -> None:
        init_spaces(self, num_envs, config, max_episode_steps, sim="mjx")
        if self.config.terrain.active:  # each env's level and where its episode started
            self.saved_fields = (*type(self).saved_fields, "terrain_level", "terrain_start")
        self._start_mjx(dynamics_for(self.quadruped, self.config))

    def saved(self, state: EnvState) -> dict[str, Any]:
        fields = {**state.episode._asdict(), "key": state.key}
        if state.ground is not None:
            fields.update(terrain_level=state.ground.level, terrain_start=state.ground.start_xy)
        return fields

    def restored(self, data: Any, fields: dict[str, Any]) -> EnvState:
        ground = None
        if "terrain_level" in self.saved_fields:
            ground = GroundState(fields["terrain_level"], fields["terrain_start"])
        return EnvState(
            data, task.Episode(*(fields[n] for n in task.Episode._fields)), fields["key"], ground
        )

    def draw(self, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        """The MuJoCo env's camera and scene."""
        if self._renderer is None:
            self._renderer = self.mujoco_env(1, self.config.replace(sim="mujoco"), 1)
            self._renderer.reset(seed=0)
        return self._renderer.render_pose(qpos)
