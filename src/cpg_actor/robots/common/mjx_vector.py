"""`MjxVectorEnv`: a robot's jitted MJX dynamics behind the two faces every MJX env shows.

* The Gymnasium ``VectorEnv`` face (``reset`` / ``step``, numpy in and out, SAME_STEP autoreset,
  ``info["final_obs"]``, ``info["episode_metrics"]``), as the robot's MuJoCo env has it, so
  evaluation, wrappers and any Gymnasium tool work on it. It copies to the host at every step.
* The trainer's tensor face (``reset_tensors`` / ``step_tensors``, torch in and out;
  :class:`cpg_actor.robots.common.torch_env.TensorEnv`): actions go to JAX and observations,
  rewards and done flags come back to torch through DLPack, on JAX's device (``self.device``),
  with no copy to the host.

A robot's MJX env subclasses it: its ``__init__`` sets the config, spaces and ``robot`` and
calls :meth:`MjxVectorEnv._start_mjx` with its dynamics, which provide jitted
``reset(keys, episode) -> (state, obs, info)`` and ``step(state, actions, episode) ->
(state, outputs)``: ``outputs`` holds ``obs``, ``reward``, ``terminated``, ``truncated``,
``final_obs``, ``episode_metrics`` and ``info`` (with ``reward_terms``); ``state`` is a JAX
pytree whose ``data`` is the batched ``mjx.Data``. ``episode`` is whatever config numbers the
dynamics take as values rather than compiled constants (None if none). The subclass also
names its ``state_key``, ``action_hint`` and ``saved_fields``, how a state is taken apart and
put together (:meth:`saved`, :meth:`restored`) and how to draw one robot (:meth:`draw`).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import torch
from gymnasium.vector import AutoresetMode, VectorEnv

from cpg_actor.robots.common.checks import check_real_tensor, real_actions
from cpg_actor.robots.common.jax_bridge import reset_keys, to_host, torch_device
from cpg_actor.robots.common.mjx_runtime import STATE_FIELDS, load
from cpg_actor.robots.common.torch_env import EnvStep

jax, _ = load()


class MjxVectorEnv(VectorEnv):
    """N robots on MJX (module docstring)."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}
    state_key: str  # the key of get_state()'s dict
    action_hint: str  # what an action row is, for error messages
    saved_fields: tuple[str, ...]  # what a saved state holds beside STATE_FIELDS
    added_fields: tuple[str, ...] = ()  # saved fields a state saved before them lacks (zeros)

    def _start_mjx(self, dynamics: Any, episode: Any = None) -> None:
        """Run on ``dynamics`` (jitted reset and step) on JAX's default device."""
        self.dynamics = dynamics
        self.jax_device = jax.devices()[0]
        self.episode = None if episode is None else jax.device_put(episode, self.jax_device)
        self.device = torch_device(self.jax_device)
        self.num_threads = None  # JAX chooses its own
        self._state = None
        self._renderer = None
        self._closed = False

    def _check_open(self, what: str) -> None:
        if self._closed:
            raise gym.error.ClosedEnvironmentError(f"{what}() on a closed environment")

    def _check_started(self, what: str) -> None:
        self._check_open(what)
        if self._state is None:
            raise RuntimeError(f"call reset() before {what}()")

    @property
    def jax_state(self) -> Any:
        """Every env's state as the dynamics step takes it; None before the first reset."""
        return self._state

    def _to_jax(self, actions: torch.Tensor):
        """Actions as a float32 JAX array on JAX's device (no copy when already there)."""
        if actions.device != self.device:
            actions = actions.to(self.device)
        return jax.dlpack.from_dlpack(actions.detach().to(torch.float32).contiguous())

    @staticmethod
    def _to_torch(value) -> torch.Tensor:
        return torch.from_dlpack(value)

    @property
    def _action_shape(self) -> tuple[int, ...]:
        return (self.num_envs, *self.single_action_space.shape)

    def _check_shape(self, shape: tuple[int, ...]) -> None:
        if tuple(shape) != self._action_shape:
            raise ValueError(f"actions must have shape {self._action_shape} ({self.action_hint}),"
                             f" got {tuple(shape)}")  # fmt: skip

    # -- the tensor face ----------------------------------------------------------------------
    def reset_tensors(self, seed: int | list[int] | None = None) -> tuple[torch.Tensor, dict]:
        """Reset every env (seeds as :meth:`reset`): the first observations, on ``device``."""
        self._check_open("reset")
        keys = reset_keys(seed, self.num_envs, self.jax_device)
        self._state, obs, info = self.dynamics.reset(keys, self.episode)
        return self._to_torch(obs), jax.tree.map(self._to_torch, info)

    def step_tensors(self, actions: torch.Tensor, check_finite: bool = True) -> EnvStep:
        """One control step from actions ``(N, J)`` (a tensor on any device).

        ``check_finite``: ValueError for NaN or inf actions, which costs a wait for the device
        at every step. False leaves the check to the caller (the trainer checks its actions
        once per rollout); a robot given NaN blows up and is terminated and reset."""
        self._check_started("step")
        self._check_shape(actions.shape)
        check_real_tensor(actions)
        if check_finite and not bool(torch.isfinite(actions).all()):
            raise ValueError("actions must be finite, got NaN or inf")
        return self._advance(self._to_jax(actions))

    def _advance(self, actions) -> EnvStep:
        self._state, out = self.dynamics.step(self._state, actions, self.episode)
        tensors = jax.tree.map(self._to_torch, out)
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
        """One control step; rewards and episode metrics as float64, as the MuJoCo envs'."""
        self._check_started("step")
        actions = real_actions(actions, f"of shape {self._action_shape}", np.float32)
        self._check_shape(actions.shape)
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
        """Everything the next step depends on, as CPU tensors (``torch.save``-able): each
        robot's ``qpos``, ``qvel`` and solver warm start, the episode bookkeeping and each
        env's random key. :meth:`set_state` continues exactly (the same numbers as a run
        never interrupted)."""
        self._check_started("get_state")
        fields = {name: getattr(self._state.data, name) for name in STATE_FIELDS}
        fields.update(self.saved(self._state))
        return {self.state_key: {k: torch.from_numpy(np.array(v)) for k, v in fields.items()}}

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`get_state` returned (ValueError if it does not fit)."""
        self._check_open("set_state")
        if not isinstance(state, dict) or not isinstance(state.get(self.state_key), dict):
            raise ValueError(f"not a state of {type(self).__name__} (get_state() makes one)")
        try:
            fields = {k: np.asarray(v.numpy()) for k, v in state[self.state_key].items()}
        except AttributeError as error:
            raise ValueError(f"not a state of {type(self).__name__} ({error!r})") from None
        names = (*STATE_FIELDS, *self.saved_fields)
        missing = [name for name in names if name not in fields and name not in self.added_fields]
        if missing:
            raise ValueError(f"the MJX state lacks {', '.join(missing)}")
        if fields["qpos"].shape[0] != self.num_envs:
            raise ValueError(f"the state has {fields['qpos'].shape[0]} envs, this env "
                             f"{self.num_envs}")  # fmt: skip
        if self._state is None:
            self.reset_tensors(seed=0)
        current = self.saved(self._state)
        for name in self.added_fields:  # a state saved before the field existed: zeros
            if name not in fields:
                fields[name] = np.zeros_like(np.asarray(current[name]))
        put = {name: jax.device_put(fields[name], self.jax_device) for name in names}
        data = self._state.data.replace(**{name: put[name] for name in STATE_FIELDS})
        self._state = self.restored(data, put)

    def saved(self, state: Any) -> dict[str, Any]:
        """The :attr:`saved_fields` of a state (here: its fields of those names)."""
        return {name: getattr(state, name) for name in self.saved_fields}

    def restored(self, data: Any, fields: dict[str, Any]) -> Any:
        """The state of ``data`` and the :attr:`saved_fields` (here: fields of those names)."""
        return type(self._state)(data=data, **{name: fields[name] for name in self.saved_fields})

    # -- rendering ----------------------------------------------------------------------------
    def render_frame(self, index: int = 0) -> np.ndarray:
        """An RGB frame ``(H, W, 3)`` of env ``index``, drawn by MuJoCo on the CPU from that
        robot's state (needs an OpenGL backend, as the MuJoCo env's)."""
        self._check_started("render_frame")
        if not 0 <= index < self.num_envs:
            raise ValueError(f"index must be in 0..{self.num_envs - 1}, got {index}")
        data = self._state.data
        qpos = np.asarray(data.qpos[index], dtype=np.float64)
        qvel = np.asarray(data.qvel[index], dtype=np.float64)
        return self.draw(qpos, qvel)

    def draw(self, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        """A frame of one robot in the state ``qpos``, ``qvel`` (float64), drawn by a MuJoCo
        env on the CPU kept in ``self._renderer`` (a robot's subclass makes it)."""
        raise NotImplementedError

    def close_extras(self, **kwargs: Any) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        self._state = None
        self._closed = True
