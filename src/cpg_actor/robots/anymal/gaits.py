"""ANYmal B's CPG presets: the quadruped gait CPGs
(:mod:`cpg_actor.robots.common.quadruped.gaits`, the gaits and their coupling) on its legs LF,
RF, LH, RH. ANYmal stands in the "X" configuration: the front knees flex towards negative
angles, the hind knees towards positive ones.
"""

from __future__ import annotations

from cpg_actor.robots.common.quadruped.gaits import (
    GAITS,
    OSCILLATOR_JOINTS,
    GaitCPGs,
    joint_map_for,
)

__all__ = ["GAITS", "OSCILLATOR_JOINTS"]  # the gaits and the joint layout's joints, re-exported

LEGS = ("LF", "RF", "LH", "RH")

# Initial parameters (eq. 3 with the drive d = the commanded forward speed, m/s): a 3 Hz step,
# hips +-(0.05 + 0.2 d) rad, knees +-(0.3 + 0.1 d) rad; convergence and coupling as the
# hopper's. Chosen on the open-loop trot (docs/quadruped.md, "The drive"): its forward speed
# grows with d (-0.08 m/s at d = 0 to 0.32 m/s at d = 1) and no robot falls. The gains are
# trained with the rest; with no drive (d = 0) the robot steps nearly in place.
QUADRUPED_INITIAL = {
    "frequency": 3.0,  # Hz, c_nu0
    "frequency_gain": 0.1,  # Hz per (m/s), c_nu1 (> 0 to be trainable)
    "amplitude": (0.05, 0.3) * 4,  # rad, c_R0 of HFE and KFE of each leg
    "amplitude_gain": (0.2, 0.1) * 4,  # rad per (m/s), c_R1
    "convergence": 20.0,  # 1/s
    "coupling_weight": 10.0,
}

# The ``leg`` layout (one oscillator per leg, a foot-space pattern):
# 3 Hz as the joint layout; r is half the foot's step, m: 1 + 8 d cm (at 3 Hz and duty 1/2 a
# step of 2 r moves the body about 4 r f: 0.5 m/s at d = 0.5 with no slip).
LEG_INITIAL = {
    "frequency": 3.0,  # Hz, c_nu0
    "frequency_gain": 0.1,  # Hz per (m/s), c_nu1
    "amplitude": 0.01,  # m, c_R0
    "amplitude_gain": 0.08,  # m per (m/s), c_R1
    "convergence": 20.0,  # 1/s
    "coupling_weight": 10.0,
}

ANYMAL_GAITS = GaitCPGs(
    legs=LEGS,
    places=LEGS,
    joints=("HFE", "KFE"),
    knee_signs=(-1, -1, 1, 1),
    joint_initial=QUADRUPED_INITIAL,
    leg_initial=LEG_INITIAL,
)
OSCILLATORS = ANYMAL_GAITS.oscillators
quadruped_cpg = ANYMAL_GAITS.joint_cpg  # the joint layout's preset
quadruped_leg_cpg = ANYMAL_GAITS.leg_cpg  # the leg layout's preset
gait_phases = ANYMAL_GAITS.gait_phases
quadruped_topology = ANYMAL_GAITS.topology
open_loop_positions = ANYMAL_GAITS.open_loop_positions
quadruped_joint_map = joint_map_for  # HFE and KFE driven, HAA held at the nominal pose
