"""ANYmal B's entry in the robot registry (:mod:`cpg_actor.robots.registry`): the quadruped's
(:func:`~cpg_actor.robots.common.quadruped.plugin.quadruped_robot`) on this folder's parts."""

from __future__ import annotations

from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.common.quadruped.plugin import quadruped_robot

ENV_ID = "cpg_actor/AnymalB-v0"  # gymnasium.make or make_vec
MJX_ENV_ID = "cpg_actor/AnymalB-mjx-v0"  # on MJX, batched only

ROBOT = quadruped_robot(
    name="anymal",
    model="anymal-b",
    config_class=QuadrupedConfig,
    env_ids=(ENV_ID, MJX_ENV_ID),
    env="cpg_actor.robots.anymal.env:AnymalEnv",
    vector_env="cpg_actor.robots.anymal.vector:AnymalVectorEnv",
    mjx_env="cpg_actor.robots.anymal.mjx:MjxAnymalVectorEnv",
    gaits="cpg_actor.robots.anymal.gaits:ANYMAL_GAITS",
    mjcf="cpg_actor.robots.anymal.mjcf",
)
