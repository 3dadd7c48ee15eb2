"""The Cho et al. 2019 baseline as agents: a classic MLP actor-critic whose actions are CPG
parameters, acting on :class:`cpg_actor.envs.cho2019.CPGParameterVectorEnv` (paper Fig. 2b).

``cho2019`` starts from a freshly initialised actor (mean action 0: the middle of every
parameter range); ``cho2019-warm`` first fits the actor's mean to the reference hopping
parameters (:mod:`cpg_actor.agents.warm_start`, paper section IV-A). Both use the extended
action set (frequency, amplitude and the hip-knee phase bias) and see the CPG state.

``cho2019-paper`` is the baseline as the paper describes it: frequency and amplitude only, the
hopper's observation only, and a warm start toward the parameters of Ijspeert et al. 2007
("warm-starting the policy network referring to the parameters in" it), not searched on
this reward: :func:`ijspeert_2007_parameters`.
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


# Ijspeert et al. 2007 (Science 315:1416, supplementary material), the limb oscillators of the
# salamander CPG: frequency nu = c_nu1 d + c_nu0, amplitude R = c_R1 d + c_R0, active for a
# drive 1 <= d <= 3 (walking). The hopper's hip and knee are taken as limb oscillators at the
# top of that range, d = 3, the fastest limb rhythm; their phase bias stays at the preset's pi,
# the antiphase of neighbouring limbs in the same model.
IJSPEERT_2007_LIMB = {"c_nu1": 0.2, "c_nu0": 0.0, "c_R1": 0.131, "c_R0": 0.131, "drive": 3.0}


def ijspeert_2007_parameters() -> np.ndarray:
    """``(nu_HFE, nu_KFE, rho_HFE, rho_KFE)`` = (0.6 Hz, 0.6 Hz, 0.524 rad, 0.524 rad)."""
    p = IJSPEERT_2007_LIMB
    nu = p["c_nu1"] * p["drive"] + p["c_nu0"]
    rho = p["c_R1"] * p["drive"] + p["c_R0"]
    return np.array([nu, nu, rho, rho])


def paper_cpg_parameter_wrapper(env: Any):
    """The CPG inside the hopper env as the paper has it: frequency and amplitude actions,
    no CPG state in the observation."""
    from cpg_actor.envs.cho2019 import CPGParameterVectorEnv

    return CPGParameterVectorEnv(env, action_set="paper", observe_cpg=False)


def warm_start_cho2019_paper(agent: Agent, normalizer, env, config: WarmStartConfig, seed: int):
    """Fit the actor's mean to :func:`ijspeert_2007_parameters` (as a paper-set action)."""
    from cpg_actor.envs.cho2019 import PAPER_PARAMETER_RANGES, parameters_to_action

    target = parameters_to_action(ijspeert_2007_parameters(), PAPER_PARAMETER_RANGES)
    return warm_start(agent, normalizer, env, target.astype(np.float32), config, seed)
