"""ANYmal B's entry in the robot registry (:mod:`cpg_actor.robots.registry`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from cpg_actor.robots.common.quadruped.config import SIMULATORS, QuadrupedConfig
from cpg_actor.robots.common.quadruped.metrics import METRICS
from cpg_actor.robots.plugin import CPGLayout, GymId, Robot

ENV_ID = "cpg_actor/AnymalB-v0"  # gymnasium.make or make_vec
MJX_ENV_ID = "cpg_actor/AnymalB-mjx-v0"  # on MJX, batched only


def make(num_envs: int, config: Any, num_threads: int | None = None) -> Any:
    if config.sim == "mjx":  # imported only when asked for (JAX, MJX)
        from cpg_actor.robots.anymal.mjx import MjxAnymalVectorEnv

        return MjxAnymalVectorEnv(num_envs, config, num_threads)
    from cpg_actor.robots.anymal.vector import AnymalVectorEnv

    return AnymalVectorEnv(num_envs, config, num_threads)


def cpg_layouts() -> dict[str, CPGLayout]:
    from cpg_actor.robots.anymal.foot_space import FootSpaceMap
    from cpg_actor.robots.anymal.gaits import (
        GAITS,
        OSCILLATOR_JOINTS,
        quadruped_cpg,
        quadruped_leg_cpg,
    )

    return {
        "joint": CPGLayout(quadruped_cpg, joints=OSCILLATOR_JOINTS, gaits=tuple(GAITS)),
        "leg": CPGLayout(quadruped_leg_cpg, pattern=FootSpaceMap, gaits=tuple(GAITS)),
    }


def mjcf(config: Any) -> str:
    from cpg_actor.robots.anymal.mjcf import simulated_mjcf

    return simulated_mjcf(config)


def observation_sources() -> tuple[dict[str, Any], ...]:
    from cpg_actor.robots.anymal.description import NOMINAL_POSE
    from cpg_actor.tasks.velocity import observation_sources

    return observation_sources(NOMINAL_POSE)


def assets() -> dict[Path, str]:
    from cpg_actor.robots.anymal.mjcf import MJCF_PATH, mjcf_text

    return {MJCF_PATH: mjcf_text()}


ROBOT = Robot(
    name="anymal",
    model="anymal-b",
    config_class=QuadrupedConfig,
    make=make,
    cpg_layouts=cpg_layouts,
    metrics=METRICS,
    gym_ids=(
        GymId(
            ENV_ID,
            "cpg_actor.robots.anymal.env:AnymalEnv",
            "cpg_actor.robots.anymal.vector:AnymalVectorEnv",
        ),
        # the MJX env's config names its simulator
        GymId(
            MJX_ENV_ID,
            "cpg_actor.robots.anymal.env:AnymalEnv",
            "cpg_actor.robots.anymal.mjx:MjxAnymalVectorEnv",
            {"config": {"sim": "mjx"}},
        ),
    ),  # fmt: skip
    mjcf=mjcf,
    observation_sources=observation_sources,
    assets=assets,
    simulators=SIMULATORS,
)
