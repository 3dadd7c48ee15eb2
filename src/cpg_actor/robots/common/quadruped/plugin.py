"""The registry entry of a quadruped on the velocity task (:func:`quadruped_robot`): what every
quadruped's ``plugin.py`` gives, from the names of its parts.

A quadruped's folder holds its description, its config, its MJCF writer (``mjcf.py``:
``mjcf_text`` and the shipped file's ``MJCF_PATH``), its envs (MuJoCo, MJX and one robot for
``gymnasium.make``: subclasses of the quadruped envs naming its
:class:`~cpg_actor.robots.common.quadruped.model.QuadrupedModel`) and its gait CPGs (a
:class:`~cpg_actor.robots.common.quadruped.gaits.GaitCPGs`). The entry names them as
"module:name" strings, imported only when asked for: the entry stays light to import.
"""

from __future__ import annotations

import importlib
from functools import partial
from pathlib import Path
from typing import Any

from cpg_actor.robots.common.mjcf import simulated_mjcf
from cpg_actor.robots.common.quadruped.agent_defaults import AGENT_DEFAULTS
from cpg_actor.robots.common.quadruped.config import SIMULATORS
from cpg_actor.robots.common.quadruped.metrics import METRICS
from cpg_actor.robots.plugin import CPGLayout, GymId, Robot, load


def quadruped_robot(
    name: str,
    model: str,
    config_class: type,
    env_ids: tuple[str, str],
    env: str,
    vector_env: str,
    mjx_env: str,
    gaits: str,
    mjcf: str,
    **fields: Any,
) -> Robot:
    """The :class:`~cpg_actor.robots.plugin.Robot` of a quadruped walking at a commanded
    velocity (:mod:`cpg_actor.tasks.velocity`).

    Args:
        name, model, config_class: as the ``Robot``'s (``config_class``: its
            :class:`~cpg_actor.robots.common.quadruped.config.QuadrupedConfig` (sub)class).
        env_ids: its Gymnasium ids, on MuJoCo and on MJX (batched only).
        env, vector_env, mjx_env: its envs, "module:Class": one robot on MuJoCo, N robots on
            MuJoCo, N robots on MJX.
        gaits: its :class:`~cpg_actor.robots.common.quadruped.gaits.GaitCPGs`, "module:NAME".
        mjcf: its MJCF writer's module.
        **fields: any other ``Robot`` field; by default its recipe is ``throughput`` and
            its ``agent_defaults`` are the quadrupeds' tuned settings.
    """
    fields = {"recipe": "throughput", "agent_defaults": AGENT_DEFAULTS, **fields}
    env_id, mjx_env_id = env_ids
    return Robot(
        name=name,
        model=model,
        config_class=config_class,
        make=partial(_make, vector_env, mjx_env),
        cpg_layouts=partial(_cpg_layouts, gaits),
        metrics=METRICS,
        gym_ids=(
            GymId(env_id, env, vector_env),
            # the MJX env's config names its simulator
            GymId(mjx_env_id, env, mjx_env, {"config": {"sim": "mjx"}}),
        ),
        mjcf=partial(_simulated_mjcf, mjcf),
        observation_sources=partial(_observation_sources, vector_env),
        assets=partial(_assets, mjcf),
        simulators=SIMULATORS,
        **fields,
    )


def _make(vector_env: str, mjx_env: str, num_envs: int, config: Any,
          num_threads: int | None = None) -> Any:  # fmt: skip
    # the MJX env imports JAX and MJX: only when asked for
    return load(mjx_env if config.sim == "mjx" else vector_env)(num_envs, config, num_threads)


def _cpg_layouts(gaits: str) -> dict[str, CPGLayout]:
    return load(gaits).layouts()


def _simulated_mjcf(mjcf: str, config: Any) -> str:
    return simulated_mjcf(load(f"{mjcf}:mjcf_text"), config)


def _observation_sources(vector_env: str, config: Any) -> tuple[dict[str, Any], ...]:
    lin_vel = bool(getattr(config, "observe_lin_vel", False))
    return load(vector_env).quadruped.observation_sources(lin_vel)


def _assets(mjcf: str) -> dict[Path, str]:
    module = importlib.import_module(mjcf)
    extra = getattr(module, "extra_assets", dict)  # e.g. another model of the robot
    return {module.MJCF_PATH: module.mjcf_text(), **extra()}
