"""Gymnasium ids of the hopper and the quadruped, registered on ``import cpg_actor`` (entry
points as strings: nothing heavy is imported until ``gymnasium.make``)."""

from __future__ import annotations

import gymnasium

ENV_ID = "cpg_actor/AnymalHopper-v0"
PYBULLET_ENV_ID = "cpg_actor/AnymalHopper-pybullet-v0"
MJX_ENV_ID = "cpg_actor/AnymalHopper-mjx-v0"  # batched only: gymnasium.make_vec
ANYMAL_ENV_ID = "cpg_actor/AnymalB-v0"  # the quadruped: gymnasium.make or make_vec
ANYMAL_MJX_ENV_ID = "cpg_actor/AnymalB-mjx-v0"  # the quadruped on MJX, batched only
EPISODE_STEPS = 500  # HopperConfig.episode_steps (a test checks they agree)
# QuadrupedConfig().episode_steps (a test checks they agree): importing the config here would
# import cpg_actor.envs, and torch with it, on every `import cpg_actor`
ANYMAL_EPISODE_STEPS = 1000


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
            # gymnasium.make on the MJX id says to use make_vec (no single-robot MJX env)
            entry_point="cpg_actor.envs.quadruped.env:AnymalEnv",
            vector_entry_point=f"cpg_actor.envs.quadruped.{vector}",
            # the MJX env's config names its simulator
            kwargs={"config": {"sim": "mjx"}} if vector.startswith("mjx") else {},
            # the env truncates its episodes itself (QuadrupedConfig.episode_seconds, 20 s);
            # a longer episode needs both, e.g. gym.make(ANYMAL_ENV_ID,
            # episode_seconds=40.0, max_episode_steps=2000)
            max_episode_steps=ANYMAL_EPISODE_STEPS,
        )
