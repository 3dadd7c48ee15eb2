"""The robots a run can train on: the one place a robot is named.

``TrainConfig.robot`` (``--robot``) names one; ``TrainConfig.env`` then holds that robot's env
config. Everything the project knows about a robot comes from its :class:`Robot` entry
(:mod:`cpg_actor.robots.plugin`): the env factory, the Gymnasium ids, the CPG layouts, the
start gait, the headline metrics and its defaults. A run looks its robot up here once, by
that name, and hands the entry down to the env, the agent and the evaluation. A robot is added
as a folder with a ``plugin.py`` and one line here (or by :func:`register_robot`).
"""

from __future__ import annotations

from typing import Any

import gymnasium

from cpg_actor.limits import brief
from cpg_actor.robots.anymal.plugin import ROBOT as ANYMAL
from cpg_actor.robots.go1.plugin import ROBOT as GO1
from cpg_actor.robots.hopper.plugin import ROBOT as HOPPER
from cpg_actor.robots.plugin import MetricInfo, Robot

ROBOTS: dict[str, Robot] = {robot.name: robot for robot in (HOPPER, ANYMAL, GO1)}
DEFAULT_ROBOT = HOPPER.name


def register_robot(robot: Robot) -> Robot:
    """Add ``robot`` to :data:`ROBOTS` (``--robot``, ``TrainConfig.robot``) and register its
    Gymnasium ids; ValueError if a robot of its name is registered already. A robot made
    outside the package registers on import of its module, before the run is built."""
    if robot.name in ROBOTS:
        raise ValueError(f"a robot named {brief(robot.name)} is already registered")
    ROBOTS[robot.name] = robot
    _register_gym_ids(robot)
    return robot


def get_robot(name: str) -> Robot:
    """The robot called ``name``; ValueError if there is none."""
    if name not in ROBOTS:
        raise ValueError(f"unknown robot {brief(name)}; available: {', '.join(ROBOTS)}")
    return ROBOTS[name]


def paper_robot() -> Robot:
    """The robot the paper's reproduction studies (``cpg-actor reproduce``'s report): the first
    whose entry names its ``paper``."""
    return next(robot for robot in ROBOTS.values() if robot.paper)


def robot_of_config(env_config: Any) -> Robot:
    """The robot whose env config ``env_config`` is."""
    for robot in ROBOTS.values():
        if type(env_config) is robot.config_class:  # a subclass is another robot's config
            return robot
    raise ValueError(f"{type(env_config).__name__} is no robot's env config")


def all_simulators() -> tuple[str, ...]:
    """Every robot's simulators, in the order of the robots (``--sim``'s choices)."""
    return tuple(dict.fromkeys(sim for robot in ROBOTS.values() for sim in robot.simulators))


def all_metrics() -> dict[str, MetricInfo]:
    """Every robot's episode metrics by name, in the order of the robots and their metrics."""
    metrics: dict[str, MetricInfo] = {}
    for robot in ROBOTS.values():
        metrics.update(robot.metrics)
    return metrics


def register() -> None:
    """Register every robot's Gymnasium ids (entry points as strings: nothing heavy is
    imported until ``gymnasium.make``). Each env truncates its episodes itself; the id's
    ``max_episode_steps`` says when, and a longer episode needs both, e.g.
    ``gym.make(ENV_ID, episode_steps=1000, max_episode_steps=1000)``."""
    for robot in ROBOTS.values():
        _register_gym_ids(robot)


def _register_gym_ids(robot: Robot) -> None:
    for gym_id in robot.gym_ids:
        if gym_id.id in gymnasium.registry:
            continue
        gymnasium.register(
            id=gym_id.id,
            entry_point=gym_id.entry_point,
            vector_entry_point=gym_id.vector_entry_point,
            kwargs=dict(gym_id.kwargs),
            max_episode_steps=robot.episode_steps,
        )
