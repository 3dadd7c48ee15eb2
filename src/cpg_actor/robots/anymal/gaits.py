"""ANYmal B's CPG presets: the quadruped gait CPGs
(:mod:`cpg_actor.robots.common.quadruped.gaits`, the gaits, their coupling and the initial
parameters, chosen on ANYmal) on its legs LF, RF, LH, RH. ANYmal stands in the "X"
configuration: the front knees flex towards negative angles, the hind knees towards positive
ones; the hind legs are the front legs mirrored (the foot-space pattern mirrors them too).
"""

from __future__ import annotations

from cpg_actor.robots.anymal_leg import kinematics
from cpg_actor.robots.common.quadruped.gaits import GaitCPGs

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
)
