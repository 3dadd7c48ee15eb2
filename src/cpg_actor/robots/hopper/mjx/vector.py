"""`MjxHopperVectorEnv`: N hoppers on MuJoCo XLA, behind two faces.

* The Gymnasium ``VectorEnv`` face (``reset`` / ``step``, numpy in and out, SAME_STEP autoreset,
  ``info["final_obs"]``, ``info["episode_metrics"]["hop_height"]``), exactly as
  :class:`~cpg_actor.robots.hopper.vector.HopperVectorEnv`'s, so evaluation, the Cho et al. wrapper
  and any Gymnasium tool work on it. It copies to the host at every step.
* The trainer's tensor face (``reset_tensors`` / ``step_tensors``, torch in and out), which
  :class:`cpg_actor.robots.common.torch_env.TorchVectorEnv` uses when an env has it: actions go to
  JAX and observations, rewards and done flags come back to torch through DLPack, on JAX's
  device (``self.device``), with no copy to the host.

The physics and the task: :mod:`cpg_actor.robots.hopper.mjx.dynamics`.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import torch
from gymnasium.vector import AutoresetMode, VectorEnv

from cpg_actor.robots.common.checks import check_real_tensor
from cpg_actor.robots.common.jax_bridge import reset_keys, to_host, torch_device
from cpg_actor.robots.common.torch_env import EnvStep
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.env import check_actions, init_vector_env
from cpg_actor.robots.hopper.mjx.dynamics import (
    STATE_FIELDS,
    EnvState,
    Episode,
    dynamics_for,
    jax,
)


class MjxHopperVectorEnv(VectorEnv):
    """N hoppers on MJX (module docstring). ``num_threads`` is accepted and ignored (JAX
    chooses its own); the other arguments are
    :class:`~cpg_actor.robots.hopper.vector.HopperVectorEnv`'s."""

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
        init_vector_env(self, num_envs, config, sim or "mjx", max_episode_steps, overrides)
        if self.config.sim != "mjx":
            raise ValueError(f"MjxHopperVectorEnv simulates with MJX, got sim={self.config.sim!r}")
        self.dynamics = dynamics_for(self.config)
        self.jax_device = jax.devices()[0]
        self.episode = Episode.of(self.config, self.jax_device)
        self.device = torch_device(self.jax_device)
        self.num_threads = None
        self._state: EnvState | None = None
        self._renderer = None
        self._closed = False

    # -- conversions --------------------------------------------------------------------------
    def _to_jax(self, actions: torch.Tensor):
        if actions.device != self.device:
            actions = actions.to(self.device)
        return jax.dlpack.from_dlpack(actions.detach().to(torch.float32).contiguous())

    @staticmethod
    def _to_torch(value) -> torch.Tensor:
        return torch.from_dlpack(value)

    def _check_open(self, what: str) -> None:
        if self._closed:
            raise gym.error.ClosedEnvironmentError(f"{what}() on a closed environment")

    def _check_started(self, what: str) -> None:
        self._check_open(what)
        if self._state is None:
            raise RuntimeError(f"call reset() before {what}()")

    @property
    def jax_state(self) -> EnvState | None:
        """Every env's state as the dynamics step takes it; None before the first reset."""
        return self._state

    # -- the tensor face ----------------------------------------------------------------------
    def reset_tensors(self, seed: int | list[int] | None = None) -> tuple[torch.Tensor, dict]:
        """Reset every env (seeds as :meth:`reset`): the first observations, on ``device``."""
        self._check_open("reset")
        keys = reset_keys(seed, self.num_envs, self.jax_device)
        self._state, obs, info = self.dynamics.reset(keys, self.episode)
        return self._to_torch(obs), jax.tree.map(self._to_torch, info)

    def step_tensors(self, actions: torch.Tensor, check_finite: bool = True) -> EnvStep:
        """One control step from desired joint positions ``(N, 2)`` (a tensor on any device).

        ``check_finite``: ValueError for NaN or inf actions, which costs a wait for the device
        at every step. False leaves the check to the caller (the trainer checks its actions
        once per rollout); a robot given NaN blows up and is terminated and reset."""
        self._check_started("step")
        if tuple(actions.shape) != (self.num_envs, 2):
            raise ValueError(
                f"actions must have shape {(self.num_envs, 2)} (desired [HFE, KFE] positions, "
                f"rad), got {tuple(actions.shape)}"
            )
        check_real_tensor(actions)
        if check_finite and not bool(torch.isfinite(actions).all()):
            raise ValueError("actions must be finite, got NaN or inf")
        return self._advance(self._to_jax(actions))

    def _advance(self, actions) -> EnvStep:
        self._state, out = self.dynamics.step(self._state, actions, self.episode)
        tensors = jax.tree.map(self._to_torch, out)
        info = dict(tensors["info"])
        done = tensors["terminated"] | tensors["truncated"]
        info.update(final_obs=tensors["final_obs"], _final_obs=done)
        info["episode_metrics"] = tensors["episode_metrics"]
        return EnvStep(
            obs=tensors["obs"],
            reward=tensors["reward"],
            terminated=tensors["terminated"],
            truncated=tensors["truncated"],
            final_obs=tensors["final_obs"],
            episode_metrics=tensors["episode_metrics"],
            reward_terms=info["reward_terms"],
            info=info,
        )

    # -- the Gymnasium face -------------------------------------------------------------------
    def reset(
        self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every env. ``seed``: an int s (env i gets s + i), a list of N ints, or None."""
        obs, info = self.reset_tensors(seed)
        return to_host(obs), to_host(info)

    def step(self, actions: Any):
        self._check_started("step")
        check_actions(actions, (self.num_envs, 2), self.config.normalized_actions)
        actions = jax.device_put(np.asarray(actions, dtype=np.float32), self.jax_device)
        out = self._advance(actions)
        info = to_host(out.info)
        return to_host(out.obs), to_host(out.reward), to_host(out.terminated), \
            to_host(out.truncated), info  # fmt: skip

    # -- checkpoints --------------------------------------------------------------------------
    def get_state(self) -> dict[str, Any]:
        """Everything the next step depends on, as CPU tensors (``torch.save``-able): each
        robot's ``qpos``, ``qvel`` and solver warm start, the desired positions, the episode
        clocks and bookkeeping, and each env's random key. :meth:`set_state` continues
        exactly (the same numbers as a run never interrupted)."""
        self._check_started("get_state")
        state = self._state
        fields = {name: getattr(state.data, name) for name in STATE_FIELDS}
        fields.update(
            desired=state.desired, elapsed=state.elapsed, standing=state.standing,
            max_hip=state.max_hip, key=state.key,
        )  # fmt: skip
        return {"mjx": {k: torch.from_numpy(np.array(v)) for k, v in fields.items()}}

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`get_state` returned (ValueError if it does not fit)."""
        self._check_open("set_state")
        try:
            fields = {k: np.asarray(v.numpy()) for k, v in state["mjx"].items()}
            missing = [k for k in (*STATE_FIELDS, "desired", "elapsed", "standing", "max_hip",
                                   "key") if k not in fields]  # fmt: skip
        except (KeyError, TypeError, AttributeError) as error:
            raise ValueError(f"not an MjxHopperVectorEnv state ({error!r})") from None
        if missing:
            raise ValueError(f"the MJX state lacks {', '.join(missing)}")
        if fields["qpos"].shape != (self.num_envs, 3):
            raise ValueError(
                f"the state has {fields['qpos'].shape[0]} envs, this env {self.num_envs}"
            )
        if self._state is None:
            self.reset_tensors(seed=0)
        put = lambda name: jax.device_put(fields[name], self.jax_device)  # noqa: E731
        data = self._state.data.replace(**{name: put(name) for name in STATE_FIELDS})
        self._state = EnvState(
            data=data, desired=put("desired"), elapsed=put("elapsed"), standing=put("standing"),
            max_hip=put("max_hip"), key=put("key"),
        )  # fmt: skip

    # -- rendering ----------------------------------------------------------------------------
    def render_frame(self, index: int = 0) -> np.ndarray:
        """An RGB frame ``(H, W, 3)`` of env ``index``, drawn by MuJoCo on the CPU from that
        robot's state (needs an OpenGL backend, as the MuJoCo env's)."""
        self._check_started("render_frame")
        if not 0 <= index < self.num_envs:
            raise ValueError(f"index must be in 0..{self.num_envs - 1}, got {index}")
        if self._renderer is None:
            from cpg_actor.robots.hopper.backends import make_backend

            self._renderer = make_backend(self.config.replace(sim="mujoco"), num_robots=1)
        data = self._state.data
        qpos = np.asarray(data.qpos[index], dtype=np.float64)[None]
        qvel = np.asarray(data.qvel[index], dtype=np.float64)[None]
        self._renderer.reset_robots(np.array([0]), qpos, qvel)
        return self._renderer.render(0, self.config.render_width, self.config.render_height)

    def close_extras(self, **kwargs: Any) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        self._state = None
        self._closed = True
