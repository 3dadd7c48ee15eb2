"""`HopperVectorEnv`: N hoppers stepped in one call, a Gymnasium ``VectorEnv`` (SAME_STEP reset).

* MuJoCo: the N robots are rows of one state array; every control step is
  ``mujoco.rollout`` over chunks of them through the physics substeps, on the calling thread
  and helper threads (``num_threads`` in all, default: the usable cores, at least 8 robots per
  thread), the joint actuators running inside MuJoCo (see
  :mod:`cpg_actor.robots.hopper.backends.mujoco_backend`).
* PyBullet: the N robots share one world, collision-filtered so that they never touch each
  other; ``num_threads`` is ignored (PyBullet holds the GIL).

Autoreset (``AutoresetMode.SAME_STEP``): when env i ends (terminated or truncated) its row of
the returned ``obs`` is already the first observation of its next episode; the last observation
of the finished episode is in ``info["final_obs"][i]`` (rows of envs that did not end hold
their current observation) and ``info["_final_obs"]`` marks the rows that ended.

Episode metrics: ``info["episode_metrics"]["hop_height"][i]`` is, for an env whose episode
ended at this step, the episode's highest hip height above the hip height it started at (m,
>= 0); NaN for the others. The trainer logs every entry of ``episode_metrics`` as it is.

Seeding: ``reset(seed=s)`` seeds env i with ``s + i`` (Gymnasium's convention), exactly as
``HopperEnv.reset(seed=s + i)`` would, so env i of the vector env and a single ``HopperEnv``
given the same seed and actions follow the same trajectory. Later autoresets continue each
env's own random stream, as ``HopperEnv.reset()`` without a seed does.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import torch
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv

from cpg_actor.robots.common.seeding import env_seeds
from cpg_actor.robots.hopper import task
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.env import check_actions, init_vector_env, resolve_config
from cpg_actor.robots.hopper.simulation import HopperSimulation
from cpg_actor.robots.hopper.task import NOMINAL_POSE


class HopperVectorEnv(VectorEnv):
    """N independent hoppers with batched stepping.

    Args:
        num_envs: N.
        config: a :class:`HopperConfig` (or a dict of its keys); defaults if None.
        num_threads: MuJoCo stepping threads; None: the usable cores (>= 8 robots each).
        sim: ``"mujoco"`` or ``"pybullet"``, overrides ``config.sim``.
        max_episode_steps: what ``gymnasium.make_vec`` passes from the registered spec; must
            equal ``episode_steps`` (the env truncates its episodes itself).
        **overrides: any :class:`HopperConfig` field.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(
        self,
        num_envs: int,
        config: HopperConfig | dict | None = None,
        num_threads: int | None = None,
        sim: str | None = None,
        max_episode_steps: int | None = None,
        **overrides: Any,
    ) -> None:
        if num_threads is not None and (
            isinstance(num_threads, bool) or not isinstance(num_threads, int) or num_threads < 1
        ):
            raise ValueError(f"num_threads must be a positive integer or None, got {num_threads!r}")
        init_vector_env(self, num_envs, config, sim, max_episode_steps, overrides)
        self.sim = HopperSimulation(self.config, self.num_envs, num_threads)
        self._rngs: list[np.random.Generator] | None = None
        self._needs_reset = True

    @property
    def num_threads(self) -> int:
        return self.sim.backend.num_threads

    @property
    def env_rngs(self) -> list[np.random.Generator] | None:
        """Each env's random generator (reset noise), as ``HopperEnv.np_random``."""
        return self._rngs

    def reset(
        self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every env. ``seed``: an int s (env i gets s + i), a list of N ints, or None."""
        if getattr(self, "sim", None) is None:
            raise gym.error.ClosedEnvironmentError(
                "reset() on a closed environment; make a new one"
            )
        if seed is None:
            if self._rngs is None:
                self._rngs = [seeding.np_random(None)[0] for _ in range(self.num_envs)]
                self.sim.seed_perturbations([None] * self.num_envs)
        else:
            seeds = env_seeds(seed, self.num_envs)
            self._rngs = [seeding.np_random(s)[0] for s in seeds]
            self._np_random, self._np_random_seed = seeding.np_random(seeds[0])
            self.sim.seed_perturbations(seeds)
        index = np.arange(self.num_envs)
        noise = np.stack([self.sim.sample_noise(rng) for rng in self._rngs])
        self.sim.reset_robots(index, noise)
        self._standing = self.sim.backend.hip_height.copy()
        self._max_hip = np.full(self.num_envs, -np.inf)
        self._needs_reset = False
        info = {
            "hip_height": self.sim.backend.hip_height.copy(),
            "foot_height": self.sim.foot_height(),
            "desired_position": np.tile(NOMINAL_POSE, (self.num_envs, 1)),
            "measured_position": self.sim.backend.joint_pos.copy(),
        }
        return self.sim.observation(), info

    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if getattr(self, "sim", None) is None:
            raise gym.error.ClosedEnvironmentError("step() on a closed environment; make a new one")
        desired = check_actions(actions, (self.num_envs, 2), self.config.normalized_actions)
        if self._needs_reset:
            raise RuntimeError("call reset() before step()")
        result = self.sim.step(desired)
        obs = result.obs
        done = result.terminated | result.truncated
        final_obs = obs.copy()
        self._max_hip = np.maximum(self._max_hip, result.hip_height)
        hop_height = task.hop_height(done, self._max_hip, self._standing)
        if done.any():
            ended = np.flatnonzero(done)
            noise = np.stack([self.sim.sample_noise(self._rngs[i]) for i in ended])
            self.sim.reset_robots(ended, noise)
            obs[ended] = self.sim.observation(ended)[ended]
            self._standing[ended] = self.sim.backend.hip_height[ended]
            self._max_hip[ended] = -np.inf
        info = {
            "reward_terms": result.reward_terms,
            "hip_height": result.hip_height,
            "foot_height": result.foot_height,
            "joint_torque": result.joint_torque,
            "desired_position": result.desired_position,
            "measured_position": result.measured_position,
            "measured_velocity": result.measured_velocity,
            "foot_position": result.foot_position,
            "final_obs": final_obs,
            "_final_obs": done,
            # per-episode metrics of the envs whose episode ended at this step (NaN elsewhere)
            "episode_metrics": {"hop_height": hop_height},
        }
        if self.config.perturbation.push:  # the envs a perturbation's push came in this step
            info["pushed"] = self.sim.pushed.copy()
        return obs, result.reward, result.terminated, result.truncated, info

    def get_state(self) -> dict[str, Any]:
        """Everything the next :meth:`step` depends on, as tensors and plain Python values
        (``torch.save``-able with ``weights_only``): the simulation (MuJoCo: the full physics
        state), the episode clocks and each env's random generator. :meth:`set_state` on an
        env of the same size and config continues exactly (MuJoCo; PyBullet restores the
        joint states, its contact caches start afresh)."""
        if getattr(self, "sim", None) is None:
            raise gym.error.ClosedEnvironmentError("get_state() on a closed environment")
        if self._needs_reset:
            raise RuntimeError("call reset() before get_state()")
        sim = {k: torch.from_numpy(np.array(v)) for k, v in self.sim.get_state().items()}
        episodes = {"standing": self._standing.copy(), "max_hip": self._max_hip.copy()}
        state = {
            "simulation": sim,
            "episodes": {k: torch.from_numpy(v) for k, v in episodes.items()},
            "rngs": [rng.bit_generator.state for rng in self._rngs],
        }
        if self.sim.draws.active:  # the perturbation's own generators and draws
            state["perturbation"] = self.sim.perturbation_state()
        return state

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`get_state` returned (ValueError if it does not fit)."""
        if getattr(self, "sim", None) is None:
            raise gym.error.ClosedEnvironmentError("set_state() on a closed environment")
        try:
            rngs = list(state["rngs"])
            simulation = {k: v.numpy() for k, v in state["simulation"].items()}
        except (KeyError, TypeError, AttributeError) as error:
            raise ValueError(f"not a HopperVectorEnv state ({error!r})") from None
        if len(rngs) != self.num_envs:
            raise ValueError(f"the state has {len(rngs)} envs, this env {self.num_envs}")
        self.sim.set_state(simulation)
        self._standing = state["episodes"]["standing"].numpy().copy()
        self._max_hip = state["episodes"]["max_hip"].numpy().copy()
        self._rngs = [seeding.np_random(0)[0] for _ in rngs]
        for rng, rng_state in zip(self._rngs, rngs, strict=True):
            rng.bit_generator.state = rng_state
        self.sim.set_perturbation_state(state.get("perturbation", {}))
        self._needs_reset = False

    def render_frame(self, index: int = 0) -> np.ndarray:
        """An RGB frame ``(H, W, 3)`` of env ``index`` (headless; see docs/hopper.md)."""
        if not 0 <= index < self.num_envs:
            raise ValueError(f"index must be in 0..{self.num_envs - 1}, got {index}")
        return self.sim.backend.render(index, self.config.render_width, self.config.render_height)

    def close_extras(self, **kwargs: Any) -> None:
        if getattr(self, "sim", None) is not None:
            self.sim.close()
            self.sim = None


def make_vector_env(
    num_envs: int,
    config: HopperConfig | dict | None = None,
    num_threads: int | None = None,
    **overrides: Any,
) -> VectorEnv:
    """N hoppers on the simulator ``config.sim`` names (or ``sim=``): a
    :class:`HopperVectorEnv` (MuJoCo, PyBullet) or, for ``"mjx"``, a
    :class:`cpg_actor.robots.hopper.mjx.MjxHopperVectorEnv` (JAX, imported only then)."""
    config = resolve_config(config, overrides.pop("sim", None), overrides)
    if config.sim == "mjx":
        from cpg_actor.robots.common import mjx_runtime as runtime

        runtime.load()  # MjxUnavailable, with the install line, if JAX or MJX is missing
        from cpg_actor.robots.hopper.mjx.vector import MjxHopperVectorEnv

        return MjxHopperVectorEnv(num_envs, config=config)
    return HopperVectorEnv(num_envs, config=config, num_threads=num_threads)
