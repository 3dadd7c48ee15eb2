"""The hopper as pure JAX functions, batched over N robots and jitted: what
:class:`~cpg_actor.robots.hopper.vector.HopperVectorEnv` computes on the CPU, computed on JAX's
device.

Same robot, same physics and the same task as the CPU simulators:

* the MJCF of :mod:`cpg_actor.robots.hopper.mjcf`, with plain ``motor`` actuators (MJX has no
  ``dcmotor``) whose torque is the actuator law of :mod:`cpg_actor.robots.common.actuator` (PD, the
  torque-speed line of the 15 rad/s motor, the 40 N m clip), computed here from the state at
  every physics substep, as MuJoCo's ``dcmotor`` does inside ``mj_step``;
* ``decimation`` substeps of ``physics_dt`` per control step (``lax.scan``), Euler
  integrator, elliptic friction cone, the configured foot friction; the Newton solver capped
  at ``mjx_iterations`` and ``mjx_ls_iterations`` (``HopperConfig``: 15 and 15, which give
  the trajectories of MuJoCo's 100 and 50 at a lower cost, docs/gpu.md);
* the task of :mod:`cpg_actor.robots.hopper.task`, the CPU envs' own functions on JAX arrays:
  the observation, the reward of paper eq. 4 (or the apex reward), blow-up termination,
  truncation after ``episode_steps``, the episode's hop height;
* resets in the nominal pose plus uniform joint noise, the foot on the ground, at rest; an env
  whose episode ended is reset in the same step (Gymnasium's SAME_STEP autoreset) and its
  last observation returned as ``final_obs``.

Differences from the CPU backends, by design: MJX computes in float32 (JAX's default; its
matrix products in full float32 also on GPUs, whose default is TensorFloat32), and its
constraint solver is not bit-identical to MuJoCo's C one, so trajectories agree within the
tolerances ``tests/robots/hopper/test_mjx.py`` states, not exactly. The solver warm start
(``qacc_warmstart``) is carried from substep to substep and from one control step to the next,
and saved with the state. Reset noise comes from one JAX key per env (threefry), not from
numpy's generator: same distribution, other numbers than the CPU envs for the same seed.
"""

from __future__ import annotations

from typing import Any, NamedTuple

from cpg_actor.robots.common.actuator import Actuator
from cpg_actor.robots.common.mjx_runtime import STATE_FIELDS, load
from cpg_actor.robots.common.mujoco_runtime import mujoco  # MUJOCO_GL chosen before mujoco
from cpg_actor.robots.hopper import task
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.mjcf import mjcf_text, set_foot_friction
from cpg_actor.robots.hopper.task import NOMINAL_POSE

jax, mjx = load()
jnp = jax.numpy


class Episode(NamedTuple):
    """The config numbers that enter the jitted functions as values, not compiled constants
    (0-dim arrays on the env's device): hoppers that differ only in them share one
    compilation, e.g. an evaluation's episode length or a test's reset."""

    steps: Any  # int32, control steps before truncation (HopperConfig.episode_steps)
    reset_noise: Any  # float32, rad (HopperConfig.reset_noise)
    reset_clearance: Any  # float32, m (HopperConfig.reset_clearance)

    @classmethod
    def of(cls, config: HopperConfig, device=None) -> Episode:
        return jax.device_put(
            cls(
                jnp.int32(config.episode_steps),
                jnp.float32(config.reset_noise),
                jnp.float32(config.reset_clearance),
            ),
            device,
        )


# the config fields the jitted functions take as values (Episode) or never read (the
# perturbation: always the nominal one on MJX): left out of the key under which dynamics_for
# shares them
SHARED_ACROSS = ("episode_steps", "reset_noise", "reset_clearance", "render_width",
                 "render_height", "perturbation", "randomize")  # fmt: skip


class EnvState(NamedTuple):
    """Everything the next step depends on, N rows each (a JAX pytree)."""

    data: Any  # mjx.Data, batched over the N robots
    desired: Any  # (N, 2) desired joint positions being tracked, rad
    elapsed: Any  # (N,) int32 control steps since the episode began
    standing: Any  # (N,) hip height at the episode's start, m
    max_hip: Any  # (N,) highest hip height of the episode so far, m
    key: Any  # (N, 2) uint32 random key of each env (reset noise)


def load_model(config: HopperConfig) -> mujoco.MjModel:
    """The hopper's MjModel with torque-controlled motors, the configured timestep and friction."""
    model = mujoco.MjModel.from_xml_string(mjcf_text(torque_control=True))
    model.opt.timestep = config.physics_dt
    model.opt.iterations = config.mjx_iterations
    model.opt.ls_iterations = config.mjx_ls_iterations
    set_foot_friction(model, config.foot_friction)
    return model


class HopperDynamics:
    """Jitted ``reset(keys, episode)`` and ``step(state, actions, episode)`` for one
    :class:`HopperConfig` (its :class:`Episode` numbers come in ``episode``)."""

    def __init__(self, config: HopperConfig) -> None:
        config.validate()
        self.config = config
        self.actuator = Actuator.from_config(config)
        self.mj_model = load_model(config)
        self.model = mjx.put_model(self.mj_model)
        self._empty = mjx.make_data(self.model)
        self._nominal = jnp.asarray(NOMINAL_POSE, dtype=jnp.float32)
        self.reset = jax.jit(self._reset)
        self.step = jax.jit(self._step)

    # -- pieces, one robot or batched ---------------------------------------------------------
    def _fresh(self, key, episode: Episode):
        """A new episode's first state for one robot, and the key advanced past its noise."""
        key, noise_key = jax.random.split(key)
        scale = episode.reset_noise
        noise = jax.random.uniform(noise_key, (2,), minval=-scale, maxval=scale)
        qpos = task.start_qpos(noise, episode.reset_clearance).astype(self._empty.qpos.dtype)
        return self._empty.replace(qpos=qpos), key

    def control(self, data, desired):
        """One control step of one robot: the actuator law, then ``mjx.step``, per substep;
        returns the new data and the joint torque, mean over the substeps (N m)."""

        def substep(carry, _):
            data, total = carry
            torque = self.actuator(desired, data.qpos[1:3], data.qvel[1:3])
            data = mjx.step(self.model, data.replace(ctrl=torque))
            return (data, total + torque), None

        start = (data, jnp.zeros(2, dtype=desired.dtype))
        # matrix products in full float32: JAX's default on recent NVIDIA GPUs is TensorFloat32
        # (10-bit mantissa), too coarse for the mass matrix and the contact solver
        with jax.default_matmul_precision("float32"):
            (data, total), _ = jax.lax.scan(substep, start, None, length=self.config.decimation)
        return data, total / self.config.decimation

    # -- the env ------------------------------------------------------------------------------
    def _reset(self, keys, episode: Episode):
        """New episodes for all N robots (``keys``: (N, 2) uint32): ``(state, obs, info)``."""
        data, keys = jax.vmap(self._fresh, in_axes=(0, None))(keys, episode)
        num = keys.shape[0]
        desired = jnp.tile(self._nominal, (num, 1))
        state = EnvState(
            data=data,
            desired=desired,
            elapsed=jnp.zeros(num, dtype=jnp.int32),
            standing=data.qpos[:, 0],
            max_hip=jnp.full(num, -jnp.inf, dtype=data.qpos.dtype),
            key=keys,
        )
        info = {
            "hip_height": data.qpos[:, 0],
            "foot_height": task.foot_height(data.qpos),
            "desired_position": desired,
            "measured_position": data.qpos[:, 1:3],
        }
        return state, task.observation(data.qpos, data.qvel, desired), info

    def _step(self, state: EnvState, actions, episode: Episode):
        """One control step of all N robots: ``(state, outputs)`` (module docstring)."""
        config = self.config
        command = task.desired_positions(actions.astype(jnp.float32), config.normalized_actions)
        desired = task.command_filter(state.desired, command, config.command_filter)
        before = state.data
        data, torque = jax.vmap(self.control)(before, desired)
        qpos, qvel = data.qpos, data.qvel
        elapsed = state.elapsed + 1

        out = task.step_outcome(config, qpos, qvel, desired, torque, elapsed, episode.steps,
                                task.com_velocity(before.qpos, before.qvel))  # fmt: skip
        max_hip = jnp.maximum(state.max_hip, out["hip_height"])
        done = out["terminated"] | out["truncated"]

        # autoreset (SAME_STEP): the envs that ended start their next episode now
        fresh, fresh_keys = jax.vmap(self._fresh, in_axes=(0, None))(state.key, episode)

        def pick(new, old):
            return jnp.where(done.reshape((-1,) + (1,) * (old.ndim - 1)), new, old)

        # only the state a step starts from is reset; mjx.step derives everything else from it
        data = data.replace(**{name: pick(getattr(fresh, name), getattr(data, name))
                               for name in STATE_FIELDS})  # fmt: skip
        next_state = EnvState(
            data=data,
            desired=pick(jnp.broadcast_to(self._nominal, desired.shape), desired),
            elapsed=jnp.where(done, 0, elapsed),
            standing=jnp.where(done, fresh.qpos[:, 0], state.standing),
            max_hip=jnp.where(done, -jnp.inf, max_hip),
            key=pick(fresh_keys, state.key),
        )
        final_obs = out.pop("obs")
        outputs = {
            "obs": task.observation(data.qpos, data.qvel, next_state.desired),
            "reward": out.pop("reward"),
            "terminated": out.pop("terminated"),
            "truncated": out.pop("truncated"),
            "final_obs": final_obs,
            "episode_metrics": {"hop_height": task.hop_height(done, max_hip, state.standing)},
            "info": out,  # reward_terms and the step's info
        }
        return next_state, outputs


_DYNAMICS: dict[tuple, HopperDynamics] = {}


def dynamics_for(config: HopperConfig) -> HopperDynamics:
    """The :class:`HopperDynamics` of ``config``, made once per process and config: envs of
    the same config (training, evaluation, a resumed run) share its jitted functions, so JAX
    compiles them once per batch size instead of once per env. Configs that differ only in
    :data:`SHARED_ACROSS` (the :class:`Episode` numbers, rendering) share them too."""
    key = tuple(sorted((k, v) for k, v in config.to_dict().items() if k not in SHARED_ACROSS))
    if key not in _DYNAMICS:
        _DYNAMICS[key] = HopperDynamics(config)
    return _DYNAMICS[key]
