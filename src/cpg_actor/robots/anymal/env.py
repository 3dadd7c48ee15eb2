"""`AnymalEnv`: one ANYmal B quadruped as a Gymnasium ``Env`` (``cpg_actor/AnymalB-v0`` with
``gymnasium.make``), the single-robot quadruped env
(:class:`~cpg_actor.robots.common.quadruped.env.QuadrupedEnv`) on ANYmal's."""

from __future__ import annotations

from cpg_actor.robots.anymal.plugin import MJX_ENV_ID
from cpg_actor.robots.anymal.vector import AnymalVectorEnv
from cpg_actor.robots.common.quadruped.env import QuadrupedEnv


class AnymalEnv(QuadrupedEnv):
    """One ANYmal B robot walking on flat ground; ``cpg_actor/AnymalB-v0``."""

    vector_env = AnymalVectorEnv
    mjx_env_id = MJX_ENV_ID
