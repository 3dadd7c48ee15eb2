"""The Go1's foot-space pattern (its ``leg`` CPG layout): the quadruped pattern
(:mod:`cpg_actor.robots.common.quadruped.foot_space`) on the Go1's leg, thigh and calf 0.213 m
each; all four legs alike (none mirrored)."""

from __future__ import annotations

from collections.abc import Sequence

from cpg_actor.robots.common.quadruped.foot_space import FootSpacePattern
from cpg_actor.robots.go1 import description as robot

# the leg in its sagittal plane (x, z; m): the knee in the thigh frame, the foot centre in the
# calf frame
THIGH = (robot.KNEE_ORIGIN[0], robot.KNEE_ORIGIN[2])
SHANK = (robot.FOOT_CENTER[0], robot.FOOT_CENTER[2])
# m: the foot's lift at mid swing, scaled from ANYmal's 0.08 by the legs' lengths (0.43 m to
# ANYmal's ~0.6 m, rounded down); the stance press as ANYmal's
CLEARANCE = 0.05
PENETRATION = 0.01


class Go1FootSpaceMap(FootSpacePattern):
    """``(phase, amplitude)`` of the 4 leg oscillators ``(B, 4)`` (FR, FL, RR, RL) -> desired
    joint positions ``(B, 12)`` (per leg abduction, hip, knee) of the Go1."""

    def __init__(
        self,
        nominal_pose: Sequence[float],
        clearance: float = CLEARANCE,
        penetration: float = PENETRATION,
    ) -> None:
        super().__init__(nominal_pose, THIGH, SHANK, clearance, penetration)
