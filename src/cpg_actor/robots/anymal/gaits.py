"""ANYmal B's CPG presets: the quadruped gait CPGs
(:mod:`cpg_actor.robots.common.quadruped.gaits`, the gaits, their coupling and the initial
parameters, chosen on ANYmal) on its legs LF, RF, LH, RH. ANYmal stands in the "X"
configuration: the front knees flex towards negative angles, the hind knees towards positive
ones; the hind legs are the front legs mirrored (the foot-space pattern mirrors them too).
"""

from __future__ import annotations

from cpg_actor.robots.anymal.description import HAA_ORIGIN
from cpg_actor.robots.anymal_leg import description as leg
from cpg_actor.robots.anymal_leg import kinematics
from cpg_actor.robots.common.quadruped.gaits import GaitCPGs

FOOT_LATERAL = leg.HFE_ORIGIN[1] + leg.KFE_ORIGIN[1] + leg.ADAPTER_ORIGIN[1]  # 0.13 m
FOOT_X = 0.4513  # m: the front feet in the nominal pose (HFE 0.4, KFE -0.8 rad)

ANYMAL_GAITS = GaitCPGs(
    legs=("LF", "RF", "LH", "RH"),
    places=("LF", "RF", "LH", "RH"),
    joints=("HFE", "KFE"),
    knee_signs=(-1, -1, 1, 1),
    # the leg (:mod:`cpg_actor.robots.anymal_leg.kinematics`): the knee in the thigh frame, the
    # foot centre in the shank frame
    thigh=kinematics.KNEE_IN_THIGH,
    shank=kinematics.FOOT_IN_SHANK,
    clearance=0.08,  # m: CPG-RL's ground clearance, ANYmal-sized
    # the planar steps: the feet in the nominal pose (x from the leg's kinematics there, y the
    # abduction axis' plus the leg's offsets along y: HFE, KFE, adapter) and their lateral
    # distance from the abduction axis
    feet=tuple(
        (sx * FOOT_X, sy * (HAA_ORIGIN[1] + FOOT_LATERAL))
        for sx, sy in ((1, 1), (1, -1), (-1, 1), (-1, -1))
    ),
    abduction_offset=FOOT_LATERAL,
)
