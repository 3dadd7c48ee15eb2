"""Agents selectable by name. An entry names the network and, if it needs one, a wrapper
around the robot's environment (the robot builds the env: ``Robot.make``).

A baseline such as ``cho2019`` (an MLP actor acting on a wrapped env whose actions are CPG
parameters) is an :class:`AgentSpec` with its ``wrapper``; the runner needs nothing else. A
robot brings the agents built for it alone (``Robot.agents``: the hopper's Cho et al.
baselines, in its folder): :data:`AGENTS` lists them too, imported on first use.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, MutableMapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from cpg_actor.agents.base import Agent, AgentConfig, observation_scale
from cpg_actor.agents.cpg_actor import CPGActorAgent
from cpg_actor.agents.mlp import MLPAgent
from cpg_actor.agents.warm_start import warm_start_mlp
from cpg_actor.robots.plugin import Robot, load
from cpg_actor.tasks.velocity import actor_entries


def env_shapes(env: Any) -> tuple[int, np.ndarray]:
    """``(obs_dim, action_scale)`` of a vector env: the action scale is the half-range
    ``(high - low) / 2`` of its action space, the unit of ``agent_config.init_std``."""
    space = env.single_action_space
    low = np.asarray(space.low, dtype=np.float32)
    high = np.asarray(space.high, dtype=np.float32)
    return int(env.single_observation_space.shape[0]), (high - low) / 2.0


@dataclass(frozen=True)
class AgentSpec:
    """``build(agent_config, env, robot) -> Agent``: the agent for an env, from its spaces
    and its ``robot`` attribute (:class:`cpg_actor.robots.spec.RobotSpec`: joints, nominal
    pose, control period) and the run's robot entry ``robot``
    (:class:`cpg_actor.robots.plugin.Robot`: the CPG layouts and the start gait);
    ``wrapper(env, agent_config, robot) -> env``, an environment around the robot's that the
    agent needs (``cho2019``: the CPG inside the env); an optional supervised warm start;
    ``trainer``, what trains it (PPO, or the open-loop search). Its tuned settings on a robot
    are the robot's (``Robot.agent_defaults``)."""

    name: str
    description: str
    build: Callable[[AgentConfig, Any, Robot], Agent]
    wrapper: Callable[[Any, AgentConfig, Robot], Any] | None = None
    # the robots (``TrainConfig.robot``) it is built for; None: any robot whose env follows the
    # contract (cho2019: its CPG sits in the hopper's env)
    robots: tuple[str, ...] | None = None
    # ``warm_start(agent, normalizer, env, TrainConfig, seed, robot) -> losses``, run once
    # before the first PPO iteration of a new run (not on resume)
    warm_start: Callable[..., list[float]] | None = None
    # it starts from agent_config.start_gait where one is set (the CPG agents, cho2019-warm,
    # mlp-warm): a comparison that counts the gait's search charges it its steps
    uses_start_gait: bool = False
    # what trains it: "ppo" (cpg_actor.training.runner.Runner) or "es", the open-loop CMA-ES search
    # (cpg_actor.training.es_runner.ESRunner)
    trainer: str = "ppo"
    # its actor leaves out the observation's privileged entries, its critic reads them (an
    # env's ``privileged_observation``, an asymmetric actor-critic): the MLP's builder
    # (``mlp``, ``mlp-warm``, whose cloning fits that actor on the actor's entries alone)
    privileged_critic: bool = False
    # its networks read the observation scaled by agent_config.observation_scales
    observation_scales: bool = False

    def wrap(self, env: Any, agent_config: AgentConfig, robot: Robot) -> Any:
        """The env this agent acts on: the robot's ``env``, wrapped if the agent declares it
        (the wrapper sees ``agent_config``: e.g. the start gait of the CPG inside the env)."""
        return env if self.wrapper is None else self.wrapper(env, agent_config, robot)


class AgentTable(MutableMapping[str, AgentSpec]):
    """The agents by name: those registered here, then those the robots bring (each robot's
    ``Robot.agents``, "module:NAME" strings, imported when the table is first read, and for a
    robot registered later, when it is read next)."""

    def __init__(self) -> None:
        self._specs: dict[str, AgentSpec] = {}
        self._loaded: set[str] = set()  # the robots' strings already imported

    def _load_robot_agents(self) -> None:
        # the robots' registry read for the agents they bring, never for a run's robot
        from cpg_actor.robots.registry import ROBOTS

        for path in (path for robot in ROBOTS.values() for path in robot.agents):
            if path not in self._loaded:
                spec = load(path)
                self._loaded.add(path)
                if spec.name in self._specs:
                    raise ValueError(f"an agent named '{spec.name}' is already registered")
                self._specs[spec.name] = spec

    def __getitem__(self, name: str) -> AgentSpec:
        self._load_robot_agents()
        return self._specs[name]

    def __setitem__(self, name: str, spec: AgentSpec) -> None:
        self._specs[name] = spec

    def __delitem__(self, name: str) -> None:
        del self._specs[name]

    def __iter__(self) -> Iterator[str]:
        self._load_robot_agents()
        return iter(self._specs)

    def __len__(self) -> int:
        self._load_robot_agents()
        return len(self._specs)


AGENTS = AgentTable()


def register_agent(spec: AgentSpec) -> AgentSpec:
    if spec.name in AGENTS:
        raise ValueError(f"an agent named '{spec.name}' is already registered")
    AGENTS[spec.name] = spec
    return spec


def get_agent_spec(name: str) -> AgentSpec:
    if name not in AGENTS:
        raise ValueError(f"unknown agent '{name}'; available: {', '.join(sorted(AGENTS))}")
    return AGENTS[name]


def build_mlp(config: AgentConfig, env: Any, robot: Robot | None = None) -> Agent:
    """Actor MLP on desired joint positions, centred on the robot's nominal pose; its actor
    reads the observation's entries but the privileged ones (the critic's alone, an env's
    ``privileged_observation``), each scaled by ``config.observation_scales`` where given."""
    names = env.robot.observation_names
    scale = observation_scale(names, config.observation_scales) if config.observation_scales \
        else None  # fmt: skip
    return MLPAgent(*env_shapes(env), config, env.robot.nominal_pose, actor_entries(names),
                    scale)  # fmt: skip


def build_cpg_actor(config: AgentConfig, env: Any, robot: Robot, feedback: bool = True) -> Agent:
    """The CPG-Actor with the CPG layout of the run's robot."""
    return CPGActorAgent(*env_shapes(env), config, env.robot, robot, feedback=feedback)


register_agent(
    AgentSpec(
        "mlp",
        "classic actor-critic: MLP actor on desired joint positions",
        build_mlp,
        privileged_critic=True,
        observation_scales=True,
    )
)
register_agent(
    AgentSpec(
        "mlp-warm",
        "the MLP actor warm-started by behaviour cloning toward the start gait's motion",
        build_mlp,
        warm_start=warm_start_mlp,
        uses_start_gait=True,
        privileged_critic=True,
        observation_scales=True,
    )
)
register_agent(
    AgentSpec(
        "cpg-actor",
        "CPG-Actor: feedback MLP -> (xi, kappa) -> Hopf CPG -> desired joint positions "
        "(from the open-loop search's gait, inside the joint range, its gradient through 8 "
        "CPG steps)",
        build_cpg_actor,
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
        lambda config, env, robot: build_cpg_actor(config, env, robot, feedback=False),
        uses_start_gait=True,
    )
)
register_agent(
    AgentSpec(
        "open-loop-es",
        "the open-loop CPG (no feedback) with its parameters V tuned by CMA-ES on the return: "
        "the search baseline, and the gait other CPG agents can start from",
        lambda config, env, robot: build_cpg_actor(config, env, robot, feedback=False),
        trainer="es",
    )
)
