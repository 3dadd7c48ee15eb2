"""`AnymalVectorEnv`: N ANYmal B quadrupeds on MuJoCo, the quadruped env
(:class:`~cpg_actor.robots.common.quadruped.vector.QuadrupedVectorEnv`: the velocity task,
SAME_STEP autoreset; its docstring says what a step returns) on ANYmal's model."""

from __future__ import annotations

from cpg_actor.robots.anymal import description as robot
from cpg_actor.robots.anymal.mjcf import mjcf_text
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.common.quadruped.model import QuadrupedModel
from cpg_actor.robots.common.quadruped.vector import QuadrupedVectorEnv

ANYMAL = QuadrupedModel.from_description(
    robot,
    name="anymal-b",
    state_key="anymal",
    config_class=QuadrupedConfig,
    base_body="base",
    mjcf_text=mjcf_text,
)


class AnymalVectorEnv(QuadrupedVectorEnv):
    """N ANYmal B robots walking on flat ground (``cpg_actor/AnymalB-v0`` with
    ``gymnasium.make_vec``). Args as :class:`QuadrupedVectorEnv`'s."""

    quadruped = ANYMAL
