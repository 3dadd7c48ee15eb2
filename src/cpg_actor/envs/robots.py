"""The robots a run can train on: each is an env config class and the vector env it makes.

``TrainConfig.robot`` names one; ``TrainConfig.env`` then holds that robot's config (the
hopper's :class:`~cpg_actor.envs.HopperConfig`, the quadruped's
:class:`~cpg_actor.envs.quadruped.QuadrupedConfig`). Agents are built from the env's
:class:`~cpg_actor.robot.RobotSpec`, so a robot is added here and nowhere else in the trainer.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class RobotEnv:
    config_class: Callable[[], Any]  # the env config dataclass (with from_dict)
    make: Callable[..., Any]  # (num_envs, config, num_threads) -> vector env
    spec_name: str  # the name of its RobotSpec (the CPG presets' and start gaits' key)
    # for a policy deployed outside the project (cpg_actor.export): the MJCF of the model its
    # MuJoCo env simulates under a config, and where each observation entry comes from in
    # that model's data (one mapping per entry; cpg_actor.export.OBSERVATION_SOURCES)
    mjcf: Callable[[Any], str]
    observation_sources: tuple[dict[str, Any], ...]


def _hopper() -> RobotEnv:
    from cpg_actor.envs import HopperConfig, make_vector_env
    from cpg_actor.envs.robot.mjcf import simulated_mjcf
    from cpg_actor.envs.simulation import OBS_SOURCES

    def make(num_envs: int, config: Any, num_threads: int | None = None) -> Any:
        return make_vector_env(num_envs, config=config, num_threads=num_threads)

    return RobotEnv(HopperConfig, make, "anymal-hopper", simulated_mjcf, OBS_SOURCES)


def _anymal() -> RobotEnv:
    from cpg_actor.envs.quadruped import QuadrupedConfig
    from cpg_actor.envs.quadruped.mjcf import simulated_mjcf
    from cpg_actor.envs.quadruped.task import OBS_SOURCES
    from cpg_actor.envs.quadruped.vector import AnymalVectorEnv

    def make(num_envs: int, config: Any, num_threads: int | None = None) -> Any:
        if config.sim == "mjx":  # imported only when asked for (JAX, MJX)
            from cpg_actor.envs.quadruped.mjx import MjxAnymalVectorEnv

            return MjxAnymalVectorEnv(num_envs, config, num_threads)
        return AnymalVectorEnv(num_envs, config, num_threads)

    return RobotEnv(QuadrupedConfig, make, "anymal-b", simulated_mjcf, OBS_SOURCES)


ROBOTS: dict[str, Callable[[], RobotEnv]] = {"hopper": _hopper, "anymal": _anymal}


def robot_env(name: str) -> RobotEnv:
    if name not in ROBOTS:
        raise ValueError(f"unknown robot {name!r}; available: {', '.join(ROBOTS)}")
    return ROBOTS[name]()


def robot_name(env_config: Any) -> str:
    """The robot whose config ``env_config`` is."""
    for name in ROBOTS:
        if isinstance(env_config, robot_env(name).config_class):
            return name
    raise ValueError(f"{type(env_config).__name__} is no robot's env config")


def make_robot_env(num_envs: int, env_config: Any, num_threads: int | None = None) -> Any:
    """The vector env of the robot whose config ``env_config`` is."""
    return robot_env(robot_name(env_config)).make(num_envs, env_config, num_threads)
