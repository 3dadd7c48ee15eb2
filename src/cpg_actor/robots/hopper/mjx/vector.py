"""`MjxHopperVectorEnv`: N hoppers on MuJoCo XLA, behind the two faces of every MJX env
(:class:`cpg_actor.robots.common.mjx_vector.MjxVectorEnv`): the Gymnasium ``VectorEnv`` face
with the info and ``info["episode_metrics"]["hop_height"]`` of
:class:`~cpg_actor.robots.hopper.vector.HopperVectorEnv`, so evaluation, the Cho et al. wrapper
and any Gymnasium tool work on it, and the trainer's tensor face (torch through DLPack, on JAX's
device).

The physics and the task: :mod:`cpg_actor.robots.hopper.mjx.dynamics`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cpg_actor.robots.common.mjx_vector import MjxVectorEnv
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.env import init_vector_env
from cpg_actor.robots.hopper.mjx.dynamics import EnvState, Episode, dynamics_for


class MjxHopperVectorEnv(MjxVectorEnv):
    """N hoppers on MJX (module docstring). ``num_threads`` is accepted and ignored (JAX
    chooses its own); the other arguments are
    :class:`~cpg_actor.robots.hopper.vector.HopperVectorEnv`'s."""

    state_key = "mjx"
    action_hint = "desired [HFE, KFE] positions, rad"
    saved_fields = EnvState._fields[1:]  # desired positions, episode clocks, keys

    def __init__(
        self,
        num_envs: int,
        config: HopperConfig | dict | None = None,
        num_threads: int | None = None,
        sim: str | None = None,
        max_episode_steps: int | None = None,
        **overrides: Any,
    ) -> None:
        init_vector_env(self, num_envs, config, sim or "mjx", max_episode_steps, overrides)
        if self.config.sim != "mjx":
            raise ValueError(f"MjxHopperVectorEnv simulates with MJX, got sim={self.config.sim!r}")
        self._start_mjx(dynamics_for(self.config), Episode.of(self.config))

    def draw(self, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        if self._renderer is None:
            from cpg_actor.robots.hopper.backends import make_backend

            self._renderer = make_backend(self.config.replace(sim="mujoco"), num_robots=1)
        self._renderer.reset_robots(np.array([0]), qpos[None], qvel[None])
        return self._renderer.render(0, self.config.render_width, self.config.render_height)
