"""The Cho et al. 2019 baseline as agents: a classic MLP actor-critic whose actions are CPG
parameters, acting on :class:`cpg_actor.envs.cho2019.CPGParameterVectorEnv` (paper Fig. 2b).

``cho2019`` starts from a freshly initialised actor (mean action 0: the middle of every
parameter range); ``cho2019-warm`` first fits the actor's mean to the reference hopping
parameters (:mod:`cpg_actor.agents.warm_start`, paper section IV-A).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cpg_actor.agents.base import Agent, AgentConfig
from cpg_actor.agents.mlp import MLPAgent
from cpg_actor.agents.warm_start import WarmStartConfig, warm_start


def cpg_parameter_wrapper(env: Any):
    """The CPG put inside the hopper env: actions become CPG parameters in [-1, 1]."""
    from cpg_actor.envs.cho2019 import CPGParameterVectorEnv

    return CPGParameterVectorEnv(env)


def build_cho2019(config: AgentConfig, env: Any) -> Agent:
    """Actor MLP 64x64 -> Gaussian over the CPG parameter actions (in [-1, 1]), centred at 0."""
    obs_dim = int(env.single_observation_space.shape[0])
    space = env.single_action_space
    action_scale = (np.asarray(space.high) - np.asarray(space.low)) / 2.0
    return MLPAgent(obs_dim, action_scale, config, nominal_pose=[0.0] * len(action_scale))


def reference_action() -> np.ndarray:
    """The reference hopping parameters as an action in [-1, 1]."""
    from cpg_actor.envs.cho2019 import parameters_to_action
    from cpg_actor.envs.cho2019_reference import REFERENCE_PARAMETERS

    return parameters_to_action(np.asarray(REFERENCE_PARAMETERS)).astype(np.float32)


def warm_start_cho2019(agent: Agent, normalizer, env, config: WarmStartConfig, seed: int):
    """Fit the actor's mean to :func:`reference_action`; returns the loss of each epoch."""
    return warm_start(agent, normalizer, env, reference_action(), config, seed)
