"""ANYmal B's foot-space pattern (its ``leg`` CPG layout): the quadruped pattern
(:mod:`cpg_actor.robots.common.quadruped.foot_space`) on ANYmal's leg
(:mod:`cpg_actor.robots.anymal_leg.kinematics`); the hind legs are the front legs mirrored."""

from __future__ import annotations

from collections.abc import Sequence

from torch import Tensor

from cpg_actor.robots.anymal_leg import kinematics
from cpg_actor.robots.common.quadruped.foot_space import FootSpacePattern, leg_foot

# the leg (front, in its own sagittal plane; m): the knee in the thigh frame, the foot centre in
# the shank frame, both relative to the joint before them; the HFE axis in the hip frame
THIGH = kinematics.KNEE_IN_THIGH
SHANK = kinematics.FOOT_IN_SHANK
HFE_ORIGIN = kinematics.HFE_ORIGIN
CLEARANCE = 0.08  # m: the foot's lift at mid swing (CPG-RL's ground clearance, ANYmal-sized)
PENETRATION = 0.01  # m: how far the stance foot is pressed below its nominal height


def front_leg_foot(hfe: Tensor, kfe: Tensor) -> tuple[Tensor, Tensor]:
    """Forward kinematics: the foot centre (x, z) relative to the HFE axis, front leg."""
    return leg_foot(hfe, kfe, THIGH, SHANK)


class FootSpaceMap(FootSpacePattern):
    """``(phase, amplitude)`` of the 4 leg oscillators ``(B, 4)`` (LF, RF, LH, RH) -> desired
    joint positions ``(B, 12)`` (per leg HAA, HFE, KFE) of ANYmal B."""

    def __init__(
        self,
        nominal_pose: Sequence[float],
        clearance: float = CLEARANCE,
        penetration: float = PENETRATION,
    ) -> None:
        super().__init__(nominal_pose, THIGH, SHANK, clearance, penetration)
