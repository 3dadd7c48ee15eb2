"""The Unitree Go1's entry in the robot registry (:mod:`cpg_actor.robots.registry`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from cpg_actor.robots.common.quadruped.config import SIMULATORS
from cpg_actor.robots.common.quadruped.metrics import METRICS
from cpg_actor.robots.go1.config import Go1Config
from cpg_actor.robots.plugin import CPGLayout, GymId, Robot

ENV_ID = "cpg_actor/Go1-v0"  # gymnasium.make or make_vec
MJX_ENV_ID = "cpg_actor/Go1-mjx-v0"  # on MJX, batched only


def make(num_envs: int, config: Any, num_threads: int | None = None) -> Any:
    if config.sim == "mjx":  # imported only when asked for (JAX, MJX)
        from cpg_actor.robots.go1.mjx import MjxGo1VectorEnv

        return MjxGo1VectorEnv(num_envs, config, num_threads)
    from cpg_actor.robots.go1.vector import Go1VectorEnv

    return Go1VectorEnv(num_envs, config, num_threads)


def cpg_layouts() -> dict[str, CPGLayout]:
    from cpg_actor.robots.common.quadruped.gaits import OSCILLATOR_JOINTS
    from cpg_actor.robots.go1.foot_space import Go1FootSpaceMap
    from cpg_actor.robots.go1.gaits import GAITS, GO1_GAITS

    return {
        "joint": CPGLayout(GO1_GAITS.joint_cpg, joints=OSCILLATOR_JOINTS, gaits=tuple(GAITS)),
        "leg": CPGLayout(GO1_GAITS.leg_cpg, pattern=Go1FootSpaceMap, gaits=tuple(GAITS)),
    }


def mjcf(config: Any) -> str:
    from cpg_actor.robots.go1.mjcf import simulated_mjcf

    return simulated_mjcf(config)


def observation_sources() -> tuple[dict[str, Any], ...]:
    from cpg_actor.robots.go1.description import NOMINAL_POSE
    from cpg_actor.tasks.velocity import observation_sources

    return observation_sources(NOMINAL_POSE)


def assets() -> dict[Path, str]:
    from cpg_actor.robots.go1.mjcf import MJCF_PATH, mjcf_text

    return {MJCF_PATH: mjcf_text()}


ROBOT = Robot(
    name="go1",
    model="unitree-go1",
    config_class=Go1Config,
    make=make,
    cpg_layouts=cpg_layouts,
    metrics=METRICS,
    gym_ids=(
        GymId(
            ENV_ID, "cpg_actor.robots.go1.env:Go1Env", "cpg_actor.robots.go1.vector:Go1VectorEnv"
        ),
        # the MJX env's config names its simulator
        GymId(
            MJX_ENV_ID,
            "cpg_actor.robots.go1.env:Go1Env",
            "cpg_actor.robots.go1.mjx:MjxGo1VectorEnv",
            {"config": {"sim": "mjx"}},
        ),
    ),
    mjcf=mjcf,
    observation_sources=observation_sources,
    assets=assets,
    simulators=SIMULATORS,
)
