"""`Go1VectorEnv`: N Unitree Go1 quadrupeds on MuJoCo, the quadruped env
(:class:`~cpg_actor.robots.common.quadruped.vector.QuadrupedVectorEnv`: the velocity task,
SAME_STEP autoreset; its docstring says what a step returns) on the Go1's model."""

from __future__ import annotations

from cpg_actor.robots.common.quadruped.model import QuadrupedModel
from cpg_actor.robots.common.quadruped.vector import QuadrupedVectorEnv
from cpg_actor.robots.go1 import description as robot
from cpg_actor.robots.go1.config import Go1Config
from cpg_actor.robots.go1.mjcf import mjcf_text

GO1 = QuadrupedModel.from_description(
    robot,
    name="unitree-go1",
    state_key="go1",
    config_class=Go1Config,
    base_body="trunk",
    mjcf_text=mjcf_text,
    camera={"distance": 1.5, "azimuth": 120.0, "elevation": -20.0},  # a robot half ANYmal's size
)


class Go1VectorEnv(QuadrupedVectorEnv):
    """N Go1 robots walking on flat ground (``cpg_actor/Go1-v0`` with ``gymnasium.make_vec``).
    Args as :class:`QuadrupedVectorEnv`'s (``config``: a :class:`Go1Config` or a dict)."""

    quadruped = GO1
