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

    ``actor_obs``: the actor reads the first ``actor_obs`` entries of the observation and the
    critic all of them (an asymmetric actor-critic: the entries after them are privileged,
    MuJoCo Playground's ``privileged_state``); None: both read all.
    """

    state_shape = (0,)

    def __init__(
        self,
        obs_dim: int,
        action_scale: Sequence[float],
        config: AgentConfig,
        nominal_pose: Sequence[float],
        actor_obs: int | None = None,
    ) -> None:
        super().__init__(obs_dim, action_scale, config)
        if actor_obs is not None and not 1 <= actor_obs <= obs_dim:
            raise ValueError(f"actor_obs must be in 1..{obs_dim} (observation entries), got "
                             f"{actor_obs!r}")  # fmt: skip
        self.actor_obs = obs_dim if actor_obs is None else int(actor_obs)
        self.actor_mlp = mlp(
            [self.actor_obs, *config.actor_hidden, self.action_dim],
            config.activation,
            config.output_gain,
        )
        self.register_buffer("nominal_pose", torch.as_tensor(nominal_pose, dtype=torch.float32))

    def log_histograms(self) -> dict[str, Tensor]:
        last = self.actor_mlp[-1]
        return {
            "actor/output_weight": last.weight.detach(),
            "actor/output_bias": last.bias.detach(),
        }

    def actor(self, obs: Tensor, state: Tensor) -> ActorOutput:
        mean = self.nominal_pose + self.action_scale * self.actor_mlp(obs[:, : self.actor_obs])
        return ActorOutput(mean, self.std(obs.shape[0]), state, {})
