"""The hopper's entry in the robot registry (:mod:`cpg_actor.robots.registry`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from cpg_actor.robots.hopper.agent_defaults import AGENT_DEFAULTS
from cpg_actor.robots.hopper.config import SIMULATORS, HopperConfig
from cpg_actor.robots.plugin import CPGLayout, GymId, MetricInfo, Robot

ENV_ID = "cpg_actor/AnymalHopper-v0"
PYBULLET_ENV_ID = "cpg_actor/AnymalHopper-pybullet-v0"
MJX_ENV_ID = "cpg_actor/AnymalHopper-mjx-v0"  # batched only: gymnasium.make_vec
START_GAIT = Path(__file__).resolve().parent / "start_gait.yaml"  # the open-loop search's


def make(num_envs: int, config: Any, num_threads: int | None = None) -> Any:
    from cpg_actor.robots.hopper.vector import make_vector_env

    return make_vector_env(num_envs, config=config, num_threads=num_threads)


def cpg_layouts() -> dict[str, CPGLayout]:
    from cpg_actor.robots.hopper.cpg import hopper_cpg

    return {"joint": CPGLayout(hopper_cpg)}


def mjcf(config: Any) -> str:
    from cpg_actor.robots.common.mjcf import simulated_mjcf
    from cpg_actor.robots.hopper.mjcf import mjcf_text

    return simulated_mjcf(mjcf_text, config)


def observation_sources(config: Any = None) -> tuple[dict[str, Any], ...]:
    from cpg_actor.robots.hopper.task import OBS_SOURCES

    return OBS_SOURCES


def assets() -> dict[Path, str]:
    from cpg_actor.robots.hopper.mjcf import MJCF_PATH, mjcf_text
    from cpg_actor.robots.hopper.urdf import URDF_PATH, urdf_text

    return {MJCF_PATH: mjcf_text(), URDF_PATH: urdf_text()}


def _gym_id(env_id: str, sim: str, vector: str) -> GymId:
    # gymnasium.make on the MJX id says to use make_vec (there is no single-robot MJX env)
    return GymId(env_id, "cpg_actor.robots.hopper.env:HopperEnv", vector, {"sim": sim})


ROBOT = Robot(
    name="hopper",
    model="anymal-hopper",
    config_class=HopperConfig,
    make=make,
    cpg_layouts=cpg_layouts,
    metrics={"hop_height": MetricInfo("hop height", "m", short="hop")},
    gym_ids=(
        _gym_id(ENV_ID, "mujoco", "cpg_actor.robots.hopper.vector:HopperVectorEnv"),
        _gym_id(PYBULLET_ENV_ID, "pybullet", "cpg_actor.robots.hopper.vector:HopperVectorEnv"),
        _gym_id(MJX_ENV_ID, "mjx", "cpg_actor.robots.hopper.mjx.vector:MjxHopperVectorEnv"),
    ),
    mjcf=mjcf,
    observation_sources=observation_sources,
    assets=assets,
    start_gait=START_GAIT,
    simulators=SIMULATORS,
    agent_defaults=AGENT_DEFAULTS,
    agents=tuple(
        f"cpg_actor.robots.hopper.agents:{name}"
        for name in ("CHO2019", "CHO2019_WARM", "CHO2019_PAPER")
    ),
    paper="cpg_actor.robots.hopper.paper:PAPER",
    commands={
        "cpg-demo": (
            "cpg_actor.robots.hopper.commands.cpg_demo",
            "integrate the hopper CPG for a few seconds and plot x, theta_dot and r_ddot to a PNG",
        ),
        "cho2019-reference": (
            "cpg_actor.robots.hopper.commands.cho2019_reference",
            "grid-search the reference hopping CPG parameters that warm-start the cho2019 baseline",
        ),
    },
)
