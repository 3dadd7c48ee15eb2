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
    MuJoCo Playground's ``privileged_state``); None: both read all. The actor takes either
    the whole observation or its first ``actor_obs`` entries alone (a deployed robot's).
    ``input_scale``: a fixed factor per observation entry, applied before the actor and the
    critic read it (``agent_config.observation_scales``: legged_gym's scaled observation);
    None: none.
    """

    state_shape = (0,)

    def __init__(
        self,
        obs_dim: int,
        action_scale: Sequence[float],
        config: AgentConfig,
        nominal_pose: Sequence[float],
        actor_obs: int | None = None,
        input_scale: Sequence[float] | None = None,
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
        scale = None
        if input_scale is not None:
            scale = torch.as_tensor(input_scale, dtype=torch.float32)
            if scale.shape != (obs_dim,):
                raise ValueError(f"input_scale needs {obs_dim} entries (the observation's), got "
                                 f"{tuple(scale.shape)}")  # fmt: skip
        # not in the state dict (checkpoints stay as they were): the config rebuilds it
        self.register_buffer("input_scale", scale, persistent=False)

    def scaled(self, obs: Tensor) -> Tensor:
        """The networks' input: ``obs`` times :attr:`input_scale` where there is one."""
        return obs if self.input_scale is None else obs * self.input_scale

    def value(self, obs: Tensor, state: Tensor) -> Tensor:
        return super().value(self.scaled(obs), state)

    def log_histograms(self) -> dict[str, Tensor]:
        last = self.actor_mlp[-1]
        return {
            "actor/output_weight": last.weight.detach(),
            "actor/output_bias": last.bias.detach(),
        }

    def actor(self, obs: Tensor, state: Tensor) -> ActorOutput:
        inputs = obs[:, : self.actor_obs]  # the whole observation or the actor's entries
        if self.input_scale is not None:
            inputs = inputs * self.input_scale[: self.actor_obs]
        mean = self.nominal_pose + self.action_scale * self.actor_mlp(inputs)
        return ActorOutput(mean, self.std(obs.shape[0]), state, {})
