"""The Unitree Go1's entry in the robot registry (:mod:`cpg_actor.robots.registry`): the
quadruped's (:func:`~cpg_actor.robots.common.quadruped.plugin.quadruped_robot`) on this folder's
parts."""

from __future__ import annotations

from cpg_actor.robots.common.quadruped.plugin import quadruped_robot
from cpg_actor.robots.go1.config import Go1Config

ENV_ID = "cpg_actor/Go1-v0"  # gymnasium.make or make_vec
MJX_ENV_ID = "cpg_actor/Go1-mjx-v0"  # on MJX, batched only

ROBOT = quadruped_robot(
    name="go1",
    model="unitree-go1",
    config_class=Go1Config,
    env_ids=(ENV_ID, MJX_ENV_ID),
    env="cpg_actor.robots.go1.env:Go1Env",
    vector_env="cpg_actor.robots.go1.vector:Go1VectorEnv",
    mjx_env="cpg_actor.robots.go1.mjx:MjxGo1VectorEnv",
    gaits="cpg_actor.robots.go1.gaits:GO1_GAITS",
    mjcf="cpg_actor.robots.go1.mjcf",
)
