"""Supervised warm start of the Cho et al. 2019 actor (paper section IV-A).

Before PPO, the actor's mean output is trained for ``epochs`` epochs toward a reference CPG
parameter set (:data:`cpg_actor.envs.cho2019_reference.REFERENCE_PARAMETERS`), on the
observations met while the reference CPG drives the hopper. Those observations also seed the
running observation normaliser, so the warm-started actor is trained on exactly the
normalised inputs it will see when PPO starts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from cpg_actor.agents.base import Agent
from cpg_actor.ppo.normalizer import RunningNormalizer


@dataclass
class WarmStartConfig:
    """Numbers of the warm start; 100 epochs as in the paper."""

    epochs: int = 100
    rollout_steps: int = 500  # control steps of reference behaviour per env
    minibatch_size: int = 1024
    learning_rate: float = 1e-3

    def validate(self) -> None:
        for name in ("epochs", "rollout_steps", "minibatch_size"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"warm_start.{name} must be a positive integer, got {value!r}")
        if not self.learning_rate > 0:
            raise ValueError(f"warm_start.learning_rate must be > 0, got {self.learning_rate!r}")


def collect_reference_observations(env, target_action: np.ndarray, steps: int, seed: int):
    """Drive every env with the constant ``target_action`` for ``steps`` steps: obs ``(T*N, D)``."""
    obs, _ = env.reset(seed=seed)
    actions = np.tile(np.asarray(target_action, dtype=np.float32), (env.num_envs, 1))
    observations = [np.asarray(obs, dtype=np.float32)]
    for _ in range(steps - 1):
        obs, *_ = env.step(actions)
        observations.append(np.asarray(obs, dtype=np.float32))
    return torch.as_tensor(np.concatenate(observations))


def warm_start(
    agent: Agent,
    normalizer: RunningNormalizer | None,
    env,
    target_action: np.ndarray,
    config: WarmStartConfig,
    seed: int,
    generator: torch.Generator | None = None,
) -> list[float]:
    """Fit the actor's mean to ``target_action`` (in action space); returns the loss per epoch.

    Only the actor's parameters move (not the critic, not the log-std). ``normalizer`` is
    updated with the reference observations first (None: no normalisation).
    """
    config.validate()
    device = agent.log_std.device
    observations = collect_reference_observations(env, target_action, config.rollout_steps, seed)
    observations = observations.to(device)
    if normalizer is not None:
        normalizer.update(observations)
        inputs = normalizer(observations)
    else:
        inputs = observations
    target = torch.as_tensor(target_action, dtype=torch.float32, device=device)
    target = target.expand(inputs.shape[0], -1)
    empty_state = agent.initial_state(inputs.shape[0])
    actor_parameters = [
        p
        for name, p in agent.named_parameters()
        if not name.startswith("critic") and name != "log_std"
    ]
    optimiser = torch.optim.Adam(actor_parameters, lr=config.learning_rate)
    losses = []
    for _ in range(config.epochs):
        order = torch.randperm(inputs.shape[0], generator=generator).to(device)
        total = 0.0
        for start in range(0, inputs.shape[0], config.minibatch_size):
            batch = order[start : start + config.minibatch_size]
            mean = agent.actor(inputs[batch], empty_state[batch]).mean
            loss = torch.mean((mean - target[batch]) ** 2)
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total += loss.item() * len(batch)
        losses.append(total / inputs.shape[0])
    return losses
