"""`Policy`: what acts in an environment, in one object: the observation normaliser, the agent,
the action bounds and the recurrent (CPG) state of every environment it drives.

One control step is :meth:`Policy.act`: normalise the observation, run the agent from each
env's state, clip the action to the action space, keep the next state. Training (with
sampling and the normaliser updating), the evaluation during training, ``cpg-actor eval``, the
video and anything that deploys a trained agent use this same step, so they cannot drift apart.
When episodes end, :meth:`end_episodes` restarts those envs' states.

Where the critic reads privileged entries the actor does not (an env's
``privileged_observation``, MuJoCo Playground's recipe), :meth:`act` also takes the actor's
entries alone (:attr:`Policy.actor_obs_dim`), the observation a robot measures: the action is
the same, the value NaN.

:func:`cpg_actor.deploy.load_policy` builds one from a run directory or a checkpoint, with no
trainer, env or optimiser.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
import torch
from torch import Tensor

from cpg_actor.agents.base import ActStep, Agent
from cpg_actor.ppo.normalizer import RunningNormalizer


class PolicyStep(NamedTuple):
    """One control step: the clipped action for the env and what training stores."""

    action: np.ndarray | Tensor  # (N, A) float32 clipped to the action space (numpy, or a
    # tensor on the policy's device with act(tensor_action=True))
    observation: Tensor  # (N, obs_dim) the normalised observation the agent acted on
    state: Tensor  # (N, *state_shape) the recurrent state before the step
    agent: ActStep  # the agent's output: sampled action, log-prob, value, mean, std, extras


class Policy:
    """``normalizer -> agent -> clip`` with the per-env recurrent state (see the module doc).

    Args:
        agent: the actor-critic.
        normalizer: the observation normaliser (frozen unless ``act(update_normalizer=True)``).
        action_low, action_high: the env's action bounds; actions are clipped to them.
        normalize_observations: False: observations go to the agent as they are.
    """

    def __init__(
        self,
        agent: Agent,
        normalizer: RunningNormalizer,
        action_low: np.ndarray,
        action_high: np.ndarray,
        normalize_observations: bool = True,
    ) -> None:
        self.agent = agent
        self.normalizer = normalizer
        self.action_low = np.asarray(action_low, dtype=np.float32)
        self.action_high = np.asarray(action_high, dtype=np.float32)
        self.normalize_observations = normalize_observations
        self.state: Tensor | None = None
        self._initial: Tensor | None = None  # every env's state at an episode start
        self.config: Any = None  # the run's TrainConfig when built by load_policy
        self.robot: Any = None  # the env's RobotSpec when built by load_policy
        self._compiled_step: Any = None  # the training step, once compile() is called

    @property
    def device(self) -> torch.device:
        """Where the agent runs; observations go there, actions come back to numpy."""
        return self.agent.log_std.device

    @property
    def obs_dim(self) -> int:
        """The env's observation entries (the critic's privileged ones included)."""
        return int(self.normalizer.mean.shape[0])

    @property
    def actor_obs_dim(self) -> int:
        """The leading observation entries the actor reads (:attr:`obs_dim` but the critic's
        privileged entries): :meth:`act` takes an observation of either size."""
        return int(getattr(self.agent, "actor_obs", self.obs_dim))

    @property
    def num_envs(self) -> int:
        if self.state is None:
            raise RuntimeError("call Policy.reset(num_envs) first")
        return self.state.shape[0]

    def reset(self, num_envs: int) -> None:
        """Start every env's recurrent state afresh (the CPG at rest, at its initial phases)."""
        self._initial = self.agent.initial_state(num_envs)  # kept for end_episodes
        self.state = self._initial.clone()

    def end_episodes(self, done: np.ndarray | Tensor) -> None:
        """Restart the state of the envs whose episode ended (``done``: (N,) bool)."""
        if self.state is None:
            raise RuntimeError("call Policy.reset(num_envs) before end_episodes()")
        # a selection on the device: no sync with the host, whatever ended
        done = torch.as_tensor(np.asarray(done) if not isinstance(done, Tensor) else done)
        rows = done.to(self.state.device).reshape(-1, *[1] * (self.state.dim() - 1))
        initial = self._initial
        if (
            initial is None
            or initial.shape != self.state.shape
            or initial.device != self.state.device
        ):
            initial = self._initial = self.agent.initial_state(len(done)).to(self.state)
        self.state = torch.where(rows, initial, self.state)

    def _bounds(self, device: torch.device) -> tuple[Tensor, Tensor]:
        if getattr(self, "_bounds_on", (None,))[0] != device:
            low = torch.as_tensor(self.action_low, device=device)
            self._bounds_on = (device, low, torch.as_tensor(self.action_high, device=device))
        return self._bounds_on[1], self._bounds_on[2]

    def normalize(self, obs: Tensor, update: bool = False) -> Tensor:
        """The agent's input; ``update`` first merges ``obs`` into the running statistics.
        An observation of the actor's entries alone is normalised by their statistics."""
        if not self.normalize_observations:
            return obs
        if update:
            self.normalizer.update(obs)
        if obs.shape[-1] == self.obs_dim:
            return self.normalizer(obs)
        return self.normalizer.leading(obs)

    def compile(self) -> None:
        """``torch.compile`` the training step (:meth:`act` with ``deterministic=False`` and
        ``update_normalizer=True``): the normaliser, the agent, the sampling and the clip in
        a few fused kernels instead of about 700 small operators per control step, which
        dominate the rollout's cost outside the simulator. The Gaussian is drawn by torch's
        own ``normal`` (``fallback_random``), so the actions are those of the eager step;
        the rest differs from it in the last bits, never from run to run.
        Evaluation and deployment (deterministic) stay eager. Needs a C++ compiler on the
        CPU; a new batch size compiles again."""
        from cpg_actor.ppo.algorithm import compile_reproducibly

        self._compiled_step = compile_reproducibly(self._step, fallback_random=True)

    def _step(
        self,
        obs: Tensor,
        state: Tensor,
        bounds: tuple[Tensor, Tensor],
        deterministic: bool,
        update_normalizer: bool,
    ) -> tuple[Tensor, Tensor, Tensor, ActStep]:
        """The tensor part of :meth:`act`: ``(clipped action, normalised obs, state, step)``;
        ``bounds``: the action space's (low, high) on the device."""
        state = self.agent.observe(obs, state)  # e.g. the CPG's drive, from raw obs
        normalized = self.normalize(obs, update=update_normalizer)
        step = self.agent.act(normalized, state, deterministic=deterministic)
        # the env's action is the sample's first entries (the agent may draw more: feedback)
        sampled = step.action[:, : self.action_low.shape[0]]
        low, high = bounds  # the same float32 clip as numpy's
        return torch.minimum(torch.maximum(sampled, low), high), normalized, state, step

    @torch.no_grad()
    def act(
        self,
        obs: np.ndarray | Tensor,
        deterministic: bool = True,
        update_normalizer: bool = False,
        tensor_action: bool = False,
    ) -> PolicyStep:
        """One control step for every env: ``obs`` (N, obs_dim) -> clipped action (N, A).
        ``obs`` may also be the actor's entries alone, (N, :attr:`actor_obs_dim`) (a robot's
        observation, without the critic's privileged entries): the same action, the value
        (``PolicyStep.agent.value``) NaN; not with ``update_normalizer``.

        ``deterministic``: the Gaussian's mean (evaluation, deployment); False samples from
        it (training). ``tensor_action``: the action stays a tensor on the policy's device
        (the trainer, whose env takes tensors: no copy to the host on a GPU), else numpy. The
        recurrent state advances; call :meth:`end_episodes` for the envs whose episode the
        step ended."""
        if self.state is None:
            raise RuntimeError("call Policy.reset(num_envs) before act()")
        if isinstance(obs, Tensor):
            obs_t = obs.to(self.device, torch.float32)
        else:
            obs_t = torch.as_tensor(np.asarray(obs, dtype=np.float32), device=self.device)
        widths = sorted({self.obs_dim, self.actor_obs_dim})
        if obs_t.dim() != 2 or obs_t.shape[0] != self.num_envs or obs_t.shape[1] not in widths:
            shapes = " or ".join(f"({self.num_envs}, {width})" for width in widths)
            raise ValueError(f"obs must have shape {shapes}, got {tuple(obs_t.shape)}")
        if update_normalizer and obs_t.shape[1] != self.obs_dim:
            raise ValueError(f"update_normalizer needs the whole observation ({self.obs_dim} "
                             f"entries), got the actor's {obs_t.shape[1]}")  # fmt: skip
        training = not deterministic and update_normalizer
        compiled = self._compiled_step if training else None
        step_fn = compiled if compiled is not None else self._step
        bounds = self._bounds(obs_t.device)
        action, normalized, state, step = step_fn(
            obs_t, self.state, bounds, deterministic, update_normalizer
        )
        if not tensor_action:
            action = action.cpu().numpy()
        self.state = step.next_state
        return PolicyStep(action, normalized, state, step)
