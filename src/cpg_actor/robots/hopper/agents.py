"""The Cho et al. 2019 baseline as agents: a classic MLP actor-critic whose actions are CPG
parameters, acting on :class:`cpg_actor.robots.hopper.cho2019.CPGParameterVectorEnv` (paper Fig.
2b). The hopper brings them (``Robot.agents``): :data:`cpg_actor.agents.AGENTS` lists them by
the registry entry's strings, imported on first use. At the agents' layer, above the hopper's.

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
from cpg_actor.agents.registry import AgentSpec
from cpg_actor.agents.start_gait import hopper_gait_parameters, start_parameters
from cpg_actor.agents.warm_start import warm_start
from cpg_actor.robots.plugin import Robot


def cpg_parameter_wrapper(
    env: Any, agent_config: AgentConfig | None = None, robot: Robot | None = None
):
    """The CPG put inside the hopper env: actions become CPG parameters in [-1, 1]. With a
    start gait (``agent_config.start_gait``, on the run's robot ``robot``, the hopper's if
    None), its CPG has the gait's convergence rate and coupling weight, the parameters the
    actions do not set."""
    from cpg_actor.robots.hopper.cho2019 import CPGParameterVectorEnv

    initial = None
    if agent_config is not None and agent_config.start_gait:
        gait = start_parameters(agent_config.start_gait, robot or _hopper())
        initial = {k: gait[k] for k in ("convergence", "coupling_weight") if k in gait}
    return CPGParameterVectorEnv(env, cpg_initial=initial)


def _hopper() -> Robot:
    from cpg_actor.robots.hopper.plugin import ROBOT

    return ROBOT


def build_cho2019(config: AgentConfig, env: Any, robot: Robot | None = None) -> Agent:
    """Actor MLP 64x64 -> Gaussian over the CPG parameter actions (in [-1, 1]), centred at 0."""
    obs_dim = int(env.single_observation_space.shape[0])
    space = env.single_action_space
    action_scale = (np.asarray(space.high) - np.asarray(space.low)) / 2.0
    return MLPAgent(obs_dim, action_scale, config, nominal_pose=[0.0] * len(action_scale))


def reference_action(start_gait: str = "", robot: Robot | None = None) -> np.ndarray:
    """The warm start's target as an action in [-1, 1]: the reference hopping parameters
    (``cpg-actor cho2019-reference``), or with ``start_gait`` the frequency, amplitude and
    phase bias of that gait (:mod:`cpg_actor.agents.start_gait`), each moved inside the
    action range by 5 % of it if it lies outside (a target on the clip would pull the
    Gaussian mean onto the edge). ``robot``: the run's (None: the hopper's)."""
    from cpg_actor.robots.hopper.cho2019 import PARAMETER_RANGES, parameters_to_action
    from cpg_actor.robots.hopper.cho2019_reference import REFERENCE_PARAMETERS

    parameters = np.asarray(REFERENCE_PARAMETERS, dtype=np.float64)
    if start_gait:
        gait = hopper_gait_parameters(start_parameters(start_gait, robot or _hopper()))
        low, high = PARAMETER_RANGES[:, 0], PARAMETER_RANGES[:, 1]
        margin = 0.05 * (high - low)
        parameters = np.clip(np.asarray(gait), low + margin, high - margin)
    return parameters_to_action(parameters).astype(np.float32)


def warm_start_cho2019(agent: Agent, normalizer, env, config, seed: int, robot: Robot):
    """Fit the actor's mean to :func:`reference_action` (``config`` the run's
    :class:`TrainConfig`, ``robot`` its robot); returns the loss of each epoch."""
    target = reference_action(config.agent_config.start_gait, robot)
    return warm_start(agent, normalizer, env, target, config.warm_start, seed)


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


def paper_cpg_parameter_wrapper(
    env: Any, agent_config: AgentConfig | None = None, robot: Robot | None = None
):
    """The CPG inside the hopper env as the paper has it: frequency and amplitude actions,
    no CPG state in the observation."""
    from cpg_actor.robots.hopper.cho2019 import CPGParameterVectorEnv

    return CPGParameterVectorEnv(env, action_set="paper", observe_cpg=False)


def warm_start_cho2019_paper(agent: Agent, normalizer, env, config, seed: int, robot: Robot):
    """Fit the actor's mean to :func:`ijspeert_2007_parameters` (as a paper-set action)."""
    from cpg_actor.robots.hopper.cho2019 import PAPER_PARAMETER_RANGES, parameters_to_action

    target = parameters_to_action(ijspeert_2007_parameters(), PAPER_PARAMETER_RANGES)
    return warm_start(agent, normalizer, env, target.astype(np.float32), config.warm_start, seed)


CHO2019 = AgentSpec(
    "cho2019",
    "Cho et al. 2019: MLP actor outputs CPG parameters; the CPG is inside the environment",
    build_cho2019,
    wrapper=cpg_parameter_wrapper,
    robots=("hopper",),
    uses_start_gait=True,
)
CHO2019_WARM = AgentSpec(
    "cho2019-warm",
    "Cho et al. 2019 with the actor warm-started toward the reference hopping parameters",
    build_cho2019,
    wrapper=cpg_parameter_wrapper,
    warm_start=warm_start_cho2019,
    robots=("hopper",),
    uses_start_gait=True,
)
CHO2019_PAPER = AgentSpec(
    "cho2019-paper",
    "Cho et al. 2019 as the paper has it: frequency and amplitude actions, no CPG state "
    "observed, warm-started toward Ijspeert et al. 2007's limb parameters",
    build_cho2019,
    wrapper=paper_cpg_parameter_wrapper,
    warm_start=warm_start_cho2019_paper,
    robots=("hopper",),
)
