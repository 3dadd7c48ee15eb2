"""A PPO run built from its :class:`~cpg_actor.config.TrainConfig`: the env, the agent, the
policy, the normalisers, PPO and the rollout storage, apart from the loop that trains them
(:mod:`cpg_actor.training.runner`).

The run's robot is looked up once, by its name (``TrainConfig.robot``), and handed down: its
entry (:class:`cpg_actor.robots.plugin.Robot`) builds the env, the agent's spec
(:func:`cpg_actor.agents.get_agent_spec`) wraps it if the agent needs it and builds the agent
from it and the robot: nothing here knows a robot or an agent's insides.
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
from cpg_actor.robots.plugin import Robot
from cpg_actor.robots.registry import get_robot
from cpg_actor.training.policy import Policy
from cpg_actor.training.seeding import seed_everything


@dataclass
class PPORun:
    """What a PPO run trains with (:func:`build_ppo_run`)."""

    device: torch.device
    robot: Robot  # the run's robot (TrainConfig.robot), resolved once
    spec: AgentSpec
    env: TorchVectorEnv  # the training envs, torch tensors on ``device``
    agent: Agent
    normalizer: RunningNormalizer  # the observations'
    policy: Policy  # the sampling control step, with every training env's CPG state
    reward_normalizer: RewardNormalizer
    ppo: PPO
    storage: RolloutStorage


def make_env(
    config: TrainConfig, robot: Robot, num_envs: int, num_threads: int | None,
    env_config: Any = None,
) -> Any:  # fmt: skip
    """The env a run's agent acts on: ``num_envs`` of ``robot``'s envs on ``env_config`` (the
    run's env config if None), wrapped as the run's agent needs (``AgentSpec.wrapper``)."""
    env_config = config.env if env_config is None else env_config
    env = robot.make(num_envs, env_config, num_threads)
    return get_agent_spec(config.agent).wrap(env, config.agent_config, robot)


def build_ppo_run(config: TrainConfig, env: Any = None) -> PPORun:
    """Seed everything, then build the run's parts in a fixed order (the same seed gives the
    same initial networks). ``env`` replaces the robot's envs (tests)."""
    torch.set_num_threads(config.torch_threads)
    device = resolve_device(config.device)
    seed_everything(config.seed)
    spec = get_agent_spec(config.agent)
    if spec.trainer != "ppo":
        raise ValueError(
            f"agent '{config.agent}' is trained by {spec.trainer}, not PPO; use "
            "cpg_actor.training.es_runner.ESRunner (cpg-actor train picks it)"
        )
    robot = get_robot(config.robot)
    if env is None:
        env = make_env(config, robot, config.num_envs, config.env_threads)
    env = TorchVectorEnv(env, device)
    if env.num_envs != config.num_envs:
        raise ValueError(f"the env has {env.num_envs} sub-envs, the config {config.num_envs}")
    action_space = env.single_action_space
    obs_dim = int(env.single_observation_space.shape[0])
    agent = spec.build(config.agent_config, env, robot)
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
    return PPORun(
        device, robot, spec, env, agent, normalizer, policy, reward_normalizer, ppo, storage
    )
