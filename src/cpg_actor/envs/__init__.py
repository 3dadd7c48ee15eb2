"""The paper's test bed: one ANYmal leg hopping on a vertical rail, on MuJoCo and PyBullet.

Gymnasium ids (registered on import): ``cpg_actor/AnymalHopper-v0`` (MuJoCo, the default) and
``cpg_actor/AnymalHopper-pybullet-v0``; ``sim=`` chooses the simulator on either. See
``docs/hopper.md``.
"""

from __future__ import annotations

from cpg_actor.envs.config import HopperConfig
from cpg_actor.envs.hopper import HopperEnv
from cpg_actor.envs.reward import REWARD_TERMS, reward_terms
from cpg_actor.envs.simulation import OBS_NAMES
from cpg_actor.envs.vector import HopperVectorEnv, make_vector_env
from cpg_actor.envs.video import write_video
from cpg_actor.registration import ENV_ID, PYBULLET_ENV_ID, register

register()

__all__ = [
    "ENV_ID",
    "OBS_NAMES",
    "PYBULLET_ENV_ID",
    "REWARD_TERMS",
    "HopperConfig",
    "HopperEnv",
    "HopperVectorEnv",
    "make_vector_env",
    "reward_terms",
    "write_video",
]
