"""Gymnasium ids of the hopper, registered on ``import cpg_actor`` (entry points as strings:
nothing heavy is imported until ``gymnasium.make``)."""

from __future__ import annotations

import gymnasium

ENV_ID = "cpg_actor/AnymalHopper-v0"
PYBULLET_ENV_ID = "cpg_actor/AnymalHopper-pybullet-v0"
MJX_ENV_ID = "cpg_actor/AnymalHopper-mjx-v0"  # batched only: gymnasium.make_vec
ANYMAL_ENV_ID = "cpg_actor/AnymalB-v0"  # the quadruped, batched only: gymnasium.make_vec
ANYMAL_MJX_ENV_ID = "cpg_actor/AnymalB-mjx-v0"  # the quadruped on MJX, batched only
EPISODE_STEPS = 500  # HopperConfig.episode_steps (a test checks they agree)


def register() -> None:
    for env_id, sim in ((ENV_ID, "mujoco"), (PYBULLET_ENV_ID, "pybullet"), (MJX_ENV_ID, "mjx")):
        if env_id in gymnasium.registry:
            continue
        vector = "mjx.vector:MjxHopperVectorEnv" if sim == "mjx" else "vector:HopperVectorEnv"
        gymnasium.register(
            id=env_id,
            # gymnasium.make on the MJX id says to use make_vec (no single-robot MJX env)
            entry_point="cpg_actor.envs.hopper:HopperEnv",
            vector_entry_point=f"cpg_actor.envs.{vector}",
            kwargs={"sim": sim},
            # the env truncates its episodes itself (HopperConfig.episode_steps, 500); this
            # makes spec.max_episode_steps say so. A longer episode needs both:
            # gym.make(ENV_ID, episode_steps=1000, max_episode_steps=1000)
            max_episode_steps=EPISODE_STEPS,
        )
    for env_id, vector in ((ANYMAL_ENV_ID, "vector:AnymalVectorEnv"),
                           (ANYMAL_MJX_ENV_ID, "mjx:MjxAnymalVectorEnv")):  # fmt: skip
        if env_id in gymnasium.registry:
            continue
        gymnasium.register(
            id=env_id,
            entry_point=None,  # no single-robot env: gymnasium.make_vec(env_id, N)
            vector_entry_point=f"cpg_actor.envs.quadruped.{vector}",
            # the MJX env's config names its simulator
            kwargs={"config": {"sim": "mjx"}} if vector.startswith("mjx") else {},
        )
