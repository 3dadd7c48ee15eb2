"""The trainer's environment contract: a batch of N envs that takes and returns torch tensors on
a declared device.

:class:`TorchVectorEnv` puts it around any Gymnasium-style vector env of this project (the
hopper's :class:`~cpg_actor.robots.hopper.vector.HopperVectorEnv`, the Cho et al. CPG wrapper, a
test double):

* ``reset(seed) -> (obs, info)``: obs ``(N, obs_dim)`` float32 on ``device``;
* ``step(actions) -> EnvStep``: observations, rewards, terminated, truncated, the final
  observations of the episodes that ended, the env's per-episode metrics (the hopper's
  ``hop_height``) and the reward terms, as tensors on ``device``; ``info`` is the wrapped
  env's own, untouched (traces, diagnostics);
* ``robot`` (:class:`cpg_actor.robots.spec.RobotSpec`), ``num_envs``, the single-env spaces,
  ``get_state`` / ``set_state`` (episodes in checkpoints) and ``close`` pass through.

What an env can do beyond that it declares by implementing a protocol, and the trainer reads it
from :attr:`TorchVectorEnv.has_tensor_face` and :attr:`TorchVectorEnv.saves_state`:

* :class:`TensorEnv`: a tensor face of its own (``reset_tensors`` / ``step_tensors``, as the
  MJX hopper, :class:`cpg_actor.robots.hopper.mjx.MjxHopperVectorEnv`). It is called through
  it: its tensors come as they are (``torch.as_tensor`` does not copy a tensor already of the
  right type and device). A simulator that runs on the CPU and speaks numpy pays one copy per
  step.
* :class:`SavableEnv`: it saves and restores its episodes in progress, so that a checkpoint
  neither resets nor cuts them.
"""

from __future__ import annotations

from typing import Any, NamedTuple, Protocol, runtime_checkable

import numpy as np
import torch
from torch import Tensor


class EnvStep(NamedTuple):
    """One step of N envs; every tensor has N rows and lives on the env's ``device``."""

    obs: Tensor  # (N, obs_dim) float32: after an autoreset, the new episode's first observation
    reward: Tensor  # (N,) the env's float type (float64 from the CPU simulators)
    terminated: Tensor  # (N,) bool: the episode ended in a terminal state
    truncated: Tensor  # (N,) bool: the episode was cut (time limit)
    final_obs: Tensor  # (N, obs_dim) float32: the last observation of the episodes that ended
    episode_metrics: dict[str, Tensor]  # (N,) float64 each, NaN where no episode ended
    reward_terms: dict[str, Tensor]  # (N,) float64 each
    info: dict[str, Any]  # the wrapped env's info, as it gave it


@runtime_checkable
class TensorEnv(Protocol):
    """An env whose own face takes and returns torch tensors on its device (module doc)."""

    def reset_tensors(self, seed: int | list[int] | None = None) -> tuple[Tensor, dict]: ...

    def step_tensors(self, actions: Tensor, check_finite: bool = True) -> EnvStep: ...


@runtime_checkable
class SavableEnv(Protocol):
    """An env that saves and restores its episodes in progress (physics, clocks, RNGs)."""

    def get_state(self) -> dict[str, Any]: ...

    def set_state(self, state: dict[str, Any]) -> None: ...


def _is_double(value: Any) -> bool:
    return getattr(value, "dtype", None) in (np.float64, torch.float64)


def _to(value: Any, device: torch.device) -> Any:
    if isinstance(value, dict):
        return {name: tensor.to(device) for name, tensor in value.items()}
    return value.to(device)


class TorchVectorEnv:
    """Torch tensors on ``device`` in and out of a Gymnasium-style vector env (module doc)."""

    def __init__(self, env: Any, device: torch.device | str = "cpu") -> None:
        self.unwrapped = env
        self.device = torch.device(device)
        self.num_envs = int(env.num_envs)
        self.single_observation_space = env.single_observation_space
        self.single_action_space = env.single_action_space
        self.robot = env.robot
        self.has_tensor_face = isinstance(env, TensorEnv)  # called through it (module doc)
        self.saves_state = isinstance(env, SavableEnv)  # its episodes go into checkpoints

    def _tensor(self, value: Any, dtype: torch.dtype) -> Tensor:
        if not isinstance(value, Tensor):
            value = np.asarray(value)
        return torch.as_tensor(value, device=self.device).to(dtype)

    def reset(self, seed: int | None = None) -> tuple[Tensor, dict[str, Any]]:
        if self.has_tensor_face:
            obs, info = self.unwrapped.reset_tensors(seed)
        else:
            obs, info = self.unwrapped.reset(seed=seed)
        return self._tensor(obs, torch.float32), info

    def step(self, actions: Tensor | np.ndarray, check_finite: bool = True) -> EnvStep:
        """One step. ``check_finite=False`` lets an env with a tensor face skip its check of
        NaN or inf actions, a wait for the device at every step (the caller checks them);
        an env that takes numpy always checks them (they are on the host anyway)."""
        if self.has_tensor_face:
            out = self.unwrapped.step_tensors(torch.as_tensor(actions), check_finite=check_finite)
            if out.obs.device == self.device:
                return out
            return EnvStep(*(_to(value, self.device) for value in out[:-1]), out.info)
        if isinstance(actions, Tensor):
            actions = actions.detach().cpu().numpy()
        obs, reward, terminated, truncated, info = self.unwrapped.step(actions)
        obs_t = self._tensor(obs, torch.float32)
        final_obs = info.get("final_obs")
        return EnvStep(
            obs=obs_t,
            reward=self._tensor(reward, torch.float64 if _is_double(reward) else torch.float32),
            terminated=self._tensor(terminated, torch.bool),
            truncated=self._tensor(truncated, torch.bool),
            final_obs=obs_t if final_obs is None else self._tensor(final_obs, torch.float32),
            episode_metrics={
                name: self._tensor(values, torch.float64)
                for name, values in info.get("episode_metrics", {}).items()
            },
            reward_terms={
                name: self._tensor(values, torch.float64)
                for name, values in info.get("reward_terms", {}).items()
            },
            info=info,
        )

    def get_state(self) -> dict[str, Any]:
        return self.unwrapped.get_state()

    def set_state(self, state: dict[str, Any]) -> None:
        self.unwrapped.set_state(state)

    def close(self) -> None:
        self.unwrapped.close()
