"""The Go1's CPG presets: the quadruped gait CPGs (:mod:`cpg_actor.robots.common.quadruped.gaits`,
the gaits, their coupling and ANYmal's initial parameters) on its legs FR, FL, RR, RL. Every
knee of the Go1 flexes towards negative angles (knees backwards on all four legs), so every knee
oscillator leads its hip's by a quarter cycle, and no leg of the foot-space pattern is mirrored.
"""

from __future__ import annotations

from cpg_actor.robots.common.quadruped.gaits import GaitCPGs
from cpg_actor.robots.go1 import description as robot

GO1_GAITS = GaitCPGs(
    legs=("FR", "FL", "RR", "RL"),
    places=("RF", "LF", "RH", "LH"),  # front right, front left, rear right, rear left
    joints=("thigh", "calf"),
    knee_signs=(-1, -1, -1, -1),
    # the leg in its sagittal plane (x, z; m), thigh and calf 0.213 m each: the knee in the thigh
    # frame, the foot centre in the calf frame
    thigh=(robot.KNEE_ORIGIN[0], robot.KNEE_ORIGIN[2]),
    shank=(robot.FOOT_CENTER[0], robot.FOOT_CENTER[2]),
    # m: the foot's lift at mid swing, scaled from ANYmal's 0.08 by the legs' lengths (0.43 m to
    # ANYmal's ~0.6 m, rounded down); the stance press as ANYmal's
    clearance=0.05,
    # the planar steps: the feet under the hip flexion axes in the nominal pose (thigh and calf
    # of equal length, knee at twice the hip's angle), the hip flexion axis outside the
    # abduction axis by THIGH_ORIGIN_Y
    feet=tuple(
        (robot.HIP_ORIGIN[0] * sx, (robot.HIP_ORIGIN[1] + robot.THIGH_ORIGIN_Y) * sy)
        for sx, sy in (robot.LEG_SIGNS[leg] for leg in robot.LEGS)
    ),
    abduction_offset=robot.THIGH_ORIGIN_Y,
)
