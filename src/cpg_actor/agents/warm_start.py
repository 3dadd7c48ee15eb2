"""Supervised warm starts: the Cho et al. 2019 actor (paper section IV-A) and ``mlp-warm``.

Before PPO, the actor's mean output is trained for ``epochs`` epochs toward a target on the
observations met while the target behaviour drives the robot: for Cho et al. a constant CPG
parameter set (the reference, or a start gait's), for ``mlp-warm`` the joint command of the
start gait's open-loop CPG at each step (behaviour cloning). Those observations also seed the
running observation normaliser, so the warm-started actor is trained on exactly the
normalised inputs it will see when PPO starts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import torch

from cpg_actor.agents.base import Agent
from cpg_actor.limits import (
    MAX_EPOCHS,
    MAX_ROLLOUT_SAMPLES,
    MAX_ROLLOUT_STEPS,
    brief,
    check_int,
)


class Normalizer(Protocol):
    """The observation normaliser the warm start seeds (PPO's ``RunningNormalizer``)."""

    def update(self, x: torch.Tensor) -> None: ...

    def __call__(self, x: torch.Tensor) -> torch.Tensor: ...


@dataclass
class WarmStartConfig:
    """Numbers of the warm start; 100 epochs as in the paper."""

    epochs: int = 100
    rollout_steps: int = 500  # control steps of reference behaviour per env
    minibatch_size: int = 1024
    learning_rate: float = 1e-3
    # std of Gaussian noise on the actions executed while the target behaviour drives the
    # robot (in the action's units); the targets stay noise-free. Wider coverage of the states
    # around the target's, so the fitted actor recovers from its own small errors in closed
    # loop (DART, Laskey et al. 2017). 0: the target alone, as in the paper
    action_noise: float = 0.0

    def validate(self) -> None:
        for name, high in (
            ("epochs", MAX_EPOCHS),
            ("rollout_steps", MAX_ROLLOUT_STEPS),
            ("minibatch_size", MAX_ROLLOUT_SAMPLES),
        ):
            check_int(getattr(self, name), f"warm_start.{name}", 1, high)
        rate, noise = self.learning_rate, self.action_noise
        if not 0 < rate < math.inf:
            raise ValueError(f"warm_start.learning_rate must be a finite number > 0, got "
                             f"{brief(rate)}")  # fmt: skip
        if not 0 <= noise < math.inf:
            raise ValueError(f"warm_start.action_noise must be a finite number >= 0, got "
                             f"{brief(noise)}")  # fmt: skip


def collect_reference_observations(
    env, target_action: np.ndarray, steps: int, seed: int, noise: float = 0.0
):
    """Drive every env with the constant ``target_action`` (plus Gaussian ``noise`` on what is
    executed, drawn from ``seed``) for ``steps`` steps: obs ``(T*N, D)``."""
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    actions = np.tile(np.asarray(target_action, dtype=np.float32), (env.num_envs, 1))
    observations = [np.asarray(obs, dtype=np.float32)]
    for _ in range(steps - 1):
        obs, *_ = env.step(executed(actions, noise, rng))
        observations.append(np.asarray(obs, dtype=np.float32))
    return torch.as_tensor(np.concatenate(observations))


def executed(actions: np.ndarray, noise: float, rng: np.random.Generator) -> np.ndarray:
    """``actions`` with Gaussian noise of std ``noise`` (none when 0)."""
    if noise == 0:
        return actions
    return (actions + rng.normal(0.0, noise, size=actions.shape)).astype(np.float32)


def warm_start(
    agent: Agent,
    normalizer: Normalizer | None,
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
    observations = collect_reference_observations(
        env, target_action, config.rollout_steps, seed, config.action_noise
    )
    target = torch.as_tensor(target_action, dtype=torch.float32)
    target = target.expand(observations.shape[0], -1)
    return fit_actor(agent, normalizer, observations, target, config, generator)


def fit_actor(
    agent: Agent,
    normalizer: Normalizer | None,
    observations: torch.Tensor,
    target: torch.Tensor,
    config: WarmStartConfig,
    generator: torch.Generator | None = None,
) -> list[float]:
    """Fit the actor's mean on raw ``observations`` ``(S, D)`` to ``target`` ``(S, A)`` by
    mean squared error; the loss per epoch. ``normalizer`` is updated with the observations
    first (None: no normalisation)."""
    config.validate()
    device = agent.log_std.device
    observations = observations.to(device)
    if normalizer is not None:
        normalizer.update(observations)
        inputs = normalizer(observations)
    else:
        inputs = observations
    target = target.to(device=device, dtype=torch.float32)
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


def collect_gait(
    env, agent_config, robot, steps: int, seed: int, noise: float = 0.0
) -> tuple[torch.Tensor, torch.Tensor]:
    """Drive every env with the open-loop CPG of ``agent_config.start_gait`` on the run's
    robot ``robot`` (its :class:`~cpg_actor.robots.plugin.Robot` entry; the CPG-Actor without
    feedback, deterministic; Gaussian ``noise`` on what is executed) for ``steps`` steps: raw
    observations ``(T*N, D)`` and the CPG's joint commands ``(T*N, A)``, clipped to the action
    space."""
    from dataclasses import replace

    from cpg_actor.agents.cpg_actor import CPGActorAgent
    from cpg_actor.agents.registry import env_shapes

    config = replace(agent_config, exploration="position", feedback_noise=0.0)
    cpg = CPGActorAgent(*env_shapes(env), config, env.robot, robot, feedback=False)
    low = torch.as_tensor(env.single_action_space.low, dtype=torch.float32)
    high = torch.as_tensor(env.single_action_space.high, dtype=torch.float32)
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    state = cpg.initial_state(env.num_envs)
    observations, commands = [], []
    with torch.no_grad():
        for _ in range(steps):
            obs_t = torch.as_tensor(np.asarray(obs, dtype=np.float32))
            out = cpg.actor(obs_t, cpg.observe(obs_t, state))
            command = torch.minimum(torch.maximum(out.mean, low), high)
            observations.append(obs_t)
            commands.append(command)
            obs, _, terminated, truncated, _ = env.step(executed(command.numpy(), noise, rng))
            done = torch.as_tensor(np.logical_or(terminated, truncated))
            fresh = cpg.initial_state(env.num_envs)
            mask = done.reshape(-1, *([1] * (state.dim() - 1)))
            state = torch.where(mask, fresh, out.next_state)
    return torch.cat(observations), torch.cat(commands)


def warm_start_mlp(agent: Agent, normalizer, env, config, seed: int, robot) -> list[float]:
    """``mlp-warm``: behaviour cloning of the start gait (``config`` the run's
    :class:`TrainConfig`): the MLP's mean fitted to the open-loop CPG's joint commands on the
    observations that CPG meets; the loss per epoch."""
    cfg = config.warm_start
    cfg.validate()
    observations, commands = collect_gait(
        env, config.agent_config, robot, cfg.rollout_steps, seed, cfg.action_noise
    )
    return fit_actor(agent, normalizer, observations, commands, cfg)
