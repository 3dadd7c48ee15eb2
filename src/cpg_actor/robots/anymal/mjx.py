"""`MjxAnymalVectorEnv`: N ANYmal B quadrupeds on MuJoCo XLA (``sim="mjx"``), the quadruped MJX
env (:mod:`cpg_actor.robots.common.quadruped.mjx`) on ANYmal's model."""

from __future__ import annotations

from cpg_actor.robots.anymal.vector import AnymalVectorEnv
from cpg_actor.robots.common.quadruped.mjx import MjxQuadrupedVectorEnv


class MjxAnymalVectorEnv(MjxQuadrupedVectorEnv):
    """N ANYmal B robots on MJX (``cpg_actor/AnymalB-mjx-v0`` with ``gymnasium.make_vec``)."""

    mujoco_env = AnymalVectorEnv
