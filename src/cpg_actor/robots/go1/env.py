"""`Go1Env`: one Unitree Go1 as a Gymnasium ``Env`` (``cpg_actor/Go1-v0`` with
``gymnasium.make``), the single-robot quadruped env
(:class:`~cpg_actor.robots.common.quadruped.env.QuadrupedEnv`) on the Go1's."""

from __future__ import annotations

from cpg_actor.robots.common.quadruped.env import QuadrupedEnv
from cpg_actor.robots.go1.plugin import MJX_ENV_ID
from cpg_actor.robots.go1.vector import Go1VectorEnv


class Go1Env(QuadrupedEnv):
    """One Go1 walking on flat ground; ``cpg_actor/Go1-v0``."""

    vector_env = Go1VectorEnv
    mjx_env_id = MJX_ENV_ID
