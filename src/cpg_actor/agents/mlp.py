"""The classic actor-critic baseline: an MLP actor on desired joint positions."""

from __future__ import annotations

from collections.abc import Sequence

import torch
from torch import Tensor

from cpg_actor.agents.base import ActorOutput, Agent, AgentConfig, mlp


class MLPAgent(Agent):
    """``mean = nominal_pose + action_scale * MLP(obs)`` (hidden ``actor_hidden``),
    state-independent log-std.

    The MLP's output is in units of the action's half-range, as a Baselines policy on an env
    whose actions span [-1, 1]. Its last layer starts small (gain ``output_gain``), so the
    initial mean is the nominal standing pose. Stateless: its recurrent state is ``(B, 0)``.
    """

    state_shape = (0,)

    def __init__(
        self,
        obs_dim: int,
        action_scale: Sequence[float],
        config: AgentConfig,
        nominal_pose: Sequence[float],
    ) -> None:
        super().__init__(obs_dim, action_scale, config)
        self.actor_mlp = mlp(
            [obs_dim, *config.actor_hidden, self.action_dim], config.activation, config.output_gain
        )
        self.register_buffer("nominal_pose", torch.as_tensor(nominal_pose, dtype=torch.float32))

    def log_histograms(self) -> dict[str, Tensor]:
        last = self.actor_mlp[-1]
        return {
            "actor/output_weight": last.weight.detach(),
            "actor/output_bias": last.bias.detach(),
        }

    def actor(self, obs: Tensor, state: Tensor) -> ActorOutput:
        mean = self.nominal_pose + self.action_scale * self.actor_mlp(obs)
        return ActorOutput(mean, self.std(obs.shape[0]), state, {})
