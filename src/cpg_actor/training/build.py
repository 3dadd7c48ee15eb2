"""A PPO run built from its :class:`~cpg_actor.config.TrainConfig`: the env, the agent, the
policy, the normalisers, PPO and the rollout storage, apart from the loop that trains them
(:mod:`cpg_actor.training.runner`).

The agent's spec (:func:`cpg_actor.agents.get_agent_spec`) gives the env and builds the agent
for it: nothing here knows a robot or an agent's insides.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch

from cpg_actor.agents import Agent, AgentSpec, get_agent_spec
from cpg_actor.config import TrainConfig
from cpg_actor.device import resolve_device
from cpg_actor.ppo import (
    PPO,
    RewardNormalizer,
    RolloutStorage,
    RunningNormalizer,
    compile_reproducibly,
)
from cpg_actor.robots.common.torch_env import TorchVectorEnv
from cpg_actor.training.policy import Policy
from cpg_actor.training.seeding import seed_everything


@dataclass
class PPORun:
    """What a PPO run trains with (:func:`build_ppo_run`)."""

    device: torch.device
    spec: AgentSpec
    env: TorchVectorEnv  # the training envs, torch tensors on ``device``
    agent: Agent
    normalizer: RunningNormalizer  # the observations'
    policy: Policy  # the sampling control step, with every training env's CPG state
    reward_normalizer: RewardNormalizer
    ppo: PPO
    storage: RolloutStorage


def build_ppo_run(config: TrainConfig, env: Any = None) -> PPORun:
    """Seed everything, then build the run's parts in a fixed order (the same seed gives the
    same initial networks). ``env`` replaces the agent spec's env factory (tests)."""
    torch.set_num_threads(config.torch_threads)
    device = resolve_device(config.device)
    seed_everything(config.seed)
    spec = get_agent_spec(config.agent)
    if spec.trainer != "ppo":
        raise ValueError(
            f"agent '{config.agent}' is trained by {spec.trainer}, not PPO; use "
            "cpg_actor.training.es_runner.ESRunner (cpg-actor train picks it)"
        )
    if env is None:
        env = spec.make_env(config.num_envs, config.env, config.env_threads, config.agent_config)
    env = TorchVectorEnv(env, device)
    if env.num_envs != config.num_envs:
        raise ValueError(f"the env has {env.num_envs} sub-envs, the config {config.num_envs}")
    action_space = env.single_action_space
    obs_dim = int(env.single_observation_space.shape[0])
    agent = spec.build(config.agent_config, env)
    agent.to(device)
    if config.ppo.bptt_steps > 1 and math.prod(agent.state_shape) == 0:
        raise ValueError(
            f"ppo.bptt_steps={config.ppo.bptt_steps} needs an agent with a recurrent state "
            f"(a CPG agent); '{config.agent}' has none: use 1"
        )
    normalizer = RunningNormalizer(obs_dim).to(device)
    policy = Policy(
        agent,
        normalizer,
        np.asarray(action_space.low, dtype=np.float32),
        np.asarray(action_space.high, dtype=np.float32),
        config.ppo.normalize_observations,
    )
    reward_normalizer = RewardNormalizer(config.num_envs, config.ppo.gamma)
    reward_normalizer.to(device)
    if config.ppo.compile:  # the rollout's policy step and reward scaling, not only the loss
        policy.compile()
        reward_normalizer.forward = compile_reproducibly(reward_normalizer.forward)
    ppo = PPO(agent, config.ppo)
    storage = RolloutStorage(
        config.ppo.num_steps,
        config.num_envs,
        obs_dim,
        agent.sample_dim,
        tuple(agent.state_shape),
        device,
    )
    return PPORun(device, spec, env, agent, normalizer, policy, reward_normalizer, ppo, storage)
