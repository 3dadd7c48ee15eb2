"""Rollout storage and generalised advantage estimation (GAE).

The storage keeps, per control step and environment, the *normalised* observation the agent
acted on and the agent's recurrent state *before* the step (the CPG state of section III-B;
an empty ``(0,)`` tensor for stateless agents). The PPO update replays one step of the agent
from exactly these two inputs, so no backpropagation through time is needed (the paper); with
``ppo.bptt_steps = k`` it replays the state from ``k - 1`` steps earlier instead
(:meth:`RolloutStorage.windows`).
"""

from __future__ import annotations

from collections.abc import Iterator

import torch
from torch import Tensor


def compute_gae(
    rewards: Tensor,
    values: Tensor,
    terminated: Tensor,
    truncated: Tensor,
    final_values: Tensor,
    last_values: Tensor,
    gamma: float,
    gae_lambda: float,
) -> tuple[Tensor, Tensor]:
    """GAE (Schulman et al. 2016) with time-limit bootstrapping; all inputs ``(T, N)`` float.

    ``delta_t = r_t + gamma * V_next_t - V_t`` where ``V_next_t`` is

    * ``V(s_{t+1})`` (``values[t+1]``, or ``last_values`` after the last step) if the episode
      goes on,
    * ``final_values[t]`` = ``V(final observation)`` if the episode was *truncated* at ``t``
      (a time limit is not a real end: bootstrap),
    * ``0`` if it *terminated* at ``t``.

    ``A_t = delta_t + gamma * lambda * (1 - done_t) * A_{t+1}`` with ``done = terminated or
    truncated`` (the next row belongs to a new episode). Returns ``(advantages, returns)``
    with ``returns = advantages + values``.
    """
    num_steps = rewards.shape[0]
    done = torch.maximum(terminated, truncated)
    advantages = torch.zeros_like(rewards)
    next_advantage = torch.zeros_like(last_values)
    for t in reversed(range(num_steps)):
        next_values = last_values if t == num_steps - 1 else values[t + 1]
        bootstrap = (1.0 - done[t]) * next_values + truncated[t] * (
            1.0 - terminated[t]
        ) * final_values[t]
        delta = rewards[t] + gamma * bootstrap - values[t]
        next_advantage = delta + gamma * gae_lambda * (1.0 - done[t]) * next_advantage
        advantages[t] = next_advantage
    return advantages, advantages + values


class RolloutStorage:
    """Fixed-size buffers ``(T, N, ...)`` for one iteration's rollout."""

    # what the agent saw and drew at each step (each minibatch holds them), then the env's outcome
    POLICY_FIELDS = (
        "observations",
        "states",
        "actions",
        "log_probs",
        "values",
        "action_mean",
        "action_std",
    )
    FIELDS = (*POLICY_FIELDS, "rewards", "terminated", "truncated", "final_values")

    def __init__(
        self,
        num_steps: int,
        num_envs: int,
        obs_dim: int,
        action_dim: int,
        state_shape: tuple[int, ...],
        device: torch.device | str = "cpu",
    ) -> None:
        t, n = num_steps, num_envs
        self.device = torch.device(device)
        zeros = lambda *shape: torch.zeros(*shape, device=self.device)  # noqa: E731
        self.num_steps, self.num_envs = num_steps, num_envs
        self.observations = zeros(t, n, obs_dim)
        self.states = zeros(t, n, *state_shape)
        self.actions = zeros(t, n, action_dim)
        self.log_probs = zeros(t, n)
        self.values = zeros(t, n)
        self.action_mean = zeros(t, n, action_dim)
        self.action_std = zeros(t, n, action_dim)
        self.rewards = zeros(t, n)
        self.terminated = zeros(t, n)
        self.truncated = zeros(t, n)
        self.final_values = zeros(t, n)
        self.advantages = zeros(t, n)
        self.returns = zeros(t, n)
        self.step = 0

    def add(self, **fields: Tensor) -> None:
        """Store one control step; every field of :attr:`FIELDS` is required."""
        if self.step >= self.num_steps:
            raise RuntimeError("rollout storage is full; call clear() first")
        missing = set(self.FIELDS) - set(fields)
        if missing:
            raise ValueError(f"missing rollout fields: {sorted(missing)}")
        for name, value in fields.items():
            getattr(self, name)[self.step].copy_(value)
        self.step += 1

    def add_policy_step(
        self, acted, rewards: Tensor, terminated: Tensor, truncated: Tensor, final_values: Tensor
    ) -> None:
        """Store one :class:`cpg_actor.training.policy.PolicyStep` (what the agent saw and
        drew) with the env's outcome of it."""
        step = acted.agent
        self.add(
            observations=acted.observation,
            states=acted.state,
            actions=step.action,
            log_probs=step.log_prob,
            values=step.value,
            action_mean=step.mean,
            action_std=step.std,
            rewards=rewards,
            terminated=terminated.float(),
            truncated=truncated.float(),
            final_values=final_values,
        )

    def clear(self) -> None:
        self.step = 0

    def compute_returns(self, last_values: Tensor, gamma: float, gae_lambda: float) -> None:
        self.advantages, self.returns = compute_gae(
            self.rewards,
            self.values,
            self.terminated,
            self.truncated,
            self.final_values,
            last_values,
            gamma,
            gae_lambda,
        )

    def windows(self, bptt_steps: int) -> dict[str, Tensor]:
        """What replaying each step's recurrent state from ``k = bptt_steps`` steps earlier
        needs, ``(T, N, ...)`` per field (see :func:`cpg_actor.ppo.algorithm.replay_states`):

        * ``window_states``: the stored state at step ``max(t - k + 1, 0)``;
        * ``window_observations``, ``window_actions``: the inputs of the k - 1 steps after it,
          at ``s - 1`` for ``s = t - k + 2 .. t`` (``(T, N, k - 1, ...)``);
        * ``window_restart``: 1 where the state at ``s`` is not the previous step's successor:
          a new episode began at ``s`` (``done[s - 1]``) or ``s`` is at or before the rollout's
          first step; ``window_restart_states``: the stored state at ``s`` (used there).
        """
        k, t = bptt_steps, self.num_steps
        steps = torch.arange(t, device=self.device)
        start = (steps - k + 1).clamp(min=0)
        # s = t - k + 2 + j for j = 0 .. k - 2: rows (T, k - 1)
        s = steps[:, None] - k + 2 + torch.arange(k - 1, device=self.device)[None, :]
        done = torch.maximum(self.terminated, self.truncated)
        previous = (s - 1).clamp(min=0)
        restart = (s <= 0)[:, :, None] | (done[previous] > 0)  # (T, k - 1, N)
        moved = lambda x: x.transpose(1, 2)  # (T, k-1, N, ...) -> (T, N, k-1, ...)  # noqa: E731
        return {
            "window_states": self.states[start],
            "window_observations": moved(self.observations[previous]),
            "window_actions": moved(self.actions[previous]),
            "window_restart": restart.transpose(1, 2).float(),
            "window_restart_states": moved(self.states[s.clamp(min=0)]),
        }

    def minibatches(self, num_minibatches: int, bptt_steps: int = 1) -> Iterator[dict[str, Tensor]]:
        """Flatten ``(T, N)`` and yield random minibatches (torch's global RNG: reproducible).

        ``bptt_steps`` > 1 adds the fields of :meth:`windows` to each minibatch."""
        batch_size = self.num_steps * self.num_envs
        if num_minibatches > batch_size:
            raise ValueError(f"{num_minibatches} minibatches for a batch of {batch_size} samples")
        flat = {
            name: getattr(self, name).flatten(0, 1)
            for name in (*self.POLICY_FIELDS, "advantages", "returns")
        }
        if bptt_steps > 1:
            flat.update({k: v.flatten(0, 1) for k, v in self.windows(bptt_steps).items()})
        order = torch.randperm(batch_size).to(self.device)  # the CPU generator on any device
        # each field gathered on its own: contiguous tensors (torch.compile's CPU kernels for
        # strided views of one shared table gave gradients that varied from run to run);
        # index_select: the same rows as value[indices], a cheaper gather on the CPU
        for indices in order.chunk(num_minibatches):
            yield {name: value.index_select(0, indices) for name, value in flat.items()}
