"""`MjxGo1VectorEnv`: N Unitree Go1 quadrupeds on MuJoCo XLA (``sim="mjx"``), the quadruped MJX
env (:mod:`cpg_actor.robots.common.quadruped.mjx`) on the Go1's model."""

from __future__ import annotations

from cpg_actor.robots.common.quadruped.mjx import MjxQuadrupedVectorEnv
from cpg_actor.robots.go1.vector import Go1VectorEnv


class MjxGo1VectorEnv(MjxQuadrupedVectorEnv):
    """N Go1 robots on MJX (``cpg_actor/Go1-mjx-v0`` with ``gymnasium.make_vec``)."""

    mujoco_env = Go1VectorEnv
