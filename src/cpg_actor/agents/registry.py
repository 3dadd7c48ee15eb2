"""Agents selectable by name. An entry names the network and, if it needs one, a wrapper
around the robot's environment.

A baseline such as ``cho2019`` (an MLP actor acting on a wrapped env whose actions are CPG
parameters) registers an :class:`AgentSpec` with its ``wrapper``; the runner needs nothing
else.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cpg_actor.agents.base import Agent, AgentConfig
from cpg_actor.agents.cho2019 import (
    build_cho2019,
    cpg_parameter_wrapper,
    paper_cpg_parameter_wrapper,
    warm_start_cho2019,
    warm_start_cho2019_paper,
)
from cpg_actor.agents.cpg_actor import CPGActorAgent
from cpg_actor.agents.mlp import MLPAgent
from cpg_actor.agents.warm_start import warm_start_mlp


def make_robot_env(num_envs: int, env_config: Any, num_threads: int | None = None) -> Any:
    """The plain vector env of the robot whose config ``env_config`` is
    (:mod:`cpg_actor.robots.registry`): actions are desired joint positions."""
    from cpg_actor.robots.registry import make_robot_env as make

    return make(num_envs, env_config, num_threads)


def env_shapes(env: Any) -> tuple[int, np.ndarray]:
    """``(obs_dim, action_scale)`` of a vector env: the action scale is the half-range
    ``(high - low) / 2`` of its action space, the unit of ``agent_config.init_std``."""
    space = env.single_action_space
    low = np.asarray(space.low, dtype=np.float32)
    high = np.asarray(space.high, dtype=np.float32)
    return int(env.single_observation_space.shape[0]), (high - low) / 2.0


@dataclass(frozen=True)
class AgentSpec:
    """``build(agent_config, env) -> Agent``: the agent for an env, from its spaces and its
    ``robot`` (:class:`cpg_actor.robots.spec.RobotSpec`: joints, nominal pose, control period);
    ``env_factory(num_envs, env_config, num_threads) -> vector env`` (the robot's env, the
    hopper by default); ``wrapper(env, agent_config) -> env``, an environment around the
    robot's that the agent needs (``cho2019``: the CPG inside the env); an optional supervised
    warm start; ``defaults``, per robot (``TrainConfig.robot``), config values (a nested
    mapping, as a preset's) that the agent trains with unless the preset, a config file or the
    command line say otherwise: its tuned settings (:func:`cpg_actor.config.compose_config`);
    ``trainer``, what trains it (PPO, or the open-loop search)."""

    name: str
    description: str
    build: Callable[[AgentConfig, Any], Agent]
    env_factory: Callable[..., Any] = make_robot_env
    wrapper: Callable[[Any], Any] | None = None
    # the robots (``TrainConfig.robot``) it is built for; None: any robot whose env follows the
    # contract (cho2019: its CPG sits in the hopper's env)
    robots: tuple[str, ...] | None = None
    # ``warm_start(agent, normalizer, env, TrainConfig, seed) -> losses``, run once before
    # the first PPO iteration of a new run (not on resume)
    warm_start: Callable[..., list[float]] | None = None
    defaults: dict[str, dict[str, Any]] = field(default_factory=dict)
    # it starts from agent_config.start_gait where one is set (the CPG agents, cho2019-warm,
    # mlp-warm): a comparison that counts the gait's search charges it its steps
    uses_start_gait: bool = False
    # what trains it: "ppo" (cpg_actor.training.runner.Runner) or "es", the open-loop CMA-ES search
    # (cpg_actor.training.es_runner.ESRunner)
    trainer: str = "ppo"

    def make_env(
        self,
        num_envs: int,
        env_config: Any,
        num_threads: int | None = None,
        agent_config: AgentConfig | None = None,
    ) -> Any:
        """The env this agent acts on: the robot's env, wrapped if the agent declares it
        (the wrapper sees ``agent_config``: e.g. the start gait of the CPG inside the env)."""
        env = self.env_factory(num_envs, env_config, num_threads)
        return env if self.wrapper is None else self.wrapper(env, agent_config)


AGENTS: dict[str, AgentSpec] = {}


def register_agent(spec: AgentSpec) -> AgentSpec:
    if spec.name in AGENTS:
        raise ValueError(f"an agent named '{spec.name}' is already registered")
    AGENTS[spec.name] = spec
    return spec


def get_agent_spec(name: str) -> AgentSpec:
    if name not in AGENTS:
        raise ValueError(f"unknown agent '{name}'; available: {', '.join(sorted(AGENTS))}")
    return AGENTS[name]


def build_mlp(config: AgentConfig, env: Any) -> Agent:
    """Actor MLP on desired joint positions, centred on the robot's nominal pose."""
    return MLPAgent(*env_shapes(env), config, env.robot.nominal_pose)


def build_cpg_actor(config: AgentConfig, env: Any, feedback: bool = True) -> Agent:
    """The CPG-Actor with the CPG preset of the env's robot."""
    return CPGActorAgent(*env_shapes(env), config, env.robot, feedback=feedback)


# The CPG-Actor at its best on the hopper: the start gait of the open-loop search, the command
# inside the joint range, and the settings chosen by tuning (docs/results/tuning): Gaussian
# noise on the joint command of 0.3 half-ranges with the gradient through 8 CPG steps.
# cpg-actor-paper is the paper's method (its preset start, position noise of 1 half-range,
# the one-step gradient).
CPG_ACTOR_DEFAULTS: dict[str, Any] = {
    "agent_config": {
        "start_gait": "search",
        "output_bound": True,
        "exploration": "position",
        "init_std": 0.3,
    },
    "ppo": {"bptt_steps": 8},
}

register_agent(
    AgentSpec(
        "mlp",
        "classic actor-critic: MLP actor on desired joint positions",
        build_mlp,
        # chosen by tuning (docs/results/tuning)
        defaults={"hopper": {"agent_config": {"init_std": 0.3}, "ppo": {"learning_rate": 1e-3}}},
    )
)
register_agent(
    AgentSpec(
        "mlp-warm",
        "the MLP actor warm-started by behaviour cloning toward the start gait's motion",
        build_mlp,
        warm_start=warm_start_mlp,
        # the warm start's noise (warm_start.action_noise) and init_std chosen by tuning
        defaults={
            "hopper": {
                "agent_config": {"start_gait": "search", "init_std": 0.3},
                "warm_start": {"action_noise": 0.1},
            }
        },
        uses_start_gait=True,
    )
)
register_agent(
    AgentSpec(
        "cpg-actor",
        "CPG-Actor: feedback MLP -> (xi, kappa) -> Hopf CPG -> desired joint positions "
        "(from the open-loop search's gait, inside the joint range, its gradient through 8 "
        "CPG steps)",
        build_cpg_actor,
        defaults={"hopper": CPG_ACTOR_DEFAULTS},
        uses_start_gait=True,
    )
)
register_agent(
    AgentSpec(
        "cpg-actor-paper",
        "the CPG-Actor exactly as the paper: the preset's start, Gaussian noise on the "
        "joint positions, the one-step gradient",
        build_cpg_actor,
        uses_start_gait=True,
    )
)
register_agent(
    AgentSpec(
        "cpg-actor-open-loop",
        "CPG-Actor without feedback (xi = kappa = 0): only the CPG parameters are trained",
        lambda config, env: build_cpg_actor(config, env, feedback=False),
        uses_start_gait=True,
    )
)
register_agent(
    AgentSpec(
        "cho2019",
        "Cho et al. 2019: MLP actor outputs CPG parameters; the CPG is inside the environment",
        build_cho2019,
        wrapper=cpg_parameter_wrapper,
        robots=("hopper",),
        uses_start_gait=True,
    )
)
register_agent(
    AgentSpec(
        "cho2019-warm",
        "Cho et al. 2019 with the actor warm-started toward the reference hopping parameters",
        build_cho2019,
        wrapper=cpg_parameter_wrapper,
        warm_start=warm_start_cho2019,
        robots=("hopper",),
        defaults={
            "hopper": {
                "agent_config": {"start_gait": "search"},
                "warm_start": {"action_noise": 0.05},
                "ppo": {"learning_rate": 1e-3},  # the best of its tuning
            }
        },
        uses_start_gait=True,
    )
)
register_agent(
    AgentSpec(
        "cho2019-paper",
        "Cho et al. 2019 as the paper has it: frequency and amplitude actions, no CPG state "
        "observed, warm-started toward Ijspeert et al. 2007's limb parameters",
        build_cho2019,
        wrapper=paper_cpg_parameter_wrapper,
        warm_start=warm_start_cho2019_paper,
        robots=("hopper",),
        # chosen by tuning (docs/results/tuning)
        defaults={"hopper": {"agent_config": {"init_std": 0.3}}},
    )
)
register_agent(
    AgentSpec(
        "open-loop-es",
        "the open-loop CPG (no feedback) with its parameters V tuned by CMA-ES on the return: "
        "the search baseline, and the gait other CPG agents can start from",
        lambda config, env: build_cpg_actor(config, env, feedback=False),
        trainer="es",
        # inside the CPG-Actor's output bound, so that the gait it finds is a start it accepts
        defaults={"hopper": {"agent_config": {"output_bound": True}}},
    )
)
