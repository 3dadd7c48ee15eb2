"""The Go1's CPG presets: the quadruped gait CPGs (:mod:`cpg_actor.robots.common.quadruped.gaits`,
the gaits and their coupling) on its legs FR, FL, RR, RL. Every knee of the Go1 flexes towards
negative angles (knees backwards on all four legs), so every knee oscillator leads its hip's by
a quarter cycle.
"""

from __future__ import annotations

from cpg_actor.robots.common.quadruped.gaits import GAITS, GaitCPGs

__all__ = ["GAITS", "GO1_GAITS"]

# Initial parameters (eq. 3, the drive d the commanded forward speed in m/s). The joint layout:
# ANYmal's 3 Hz step, hips +-(0.05 + 0.2 d) rad, knees +-(0.3 + 0.1 d) rad (angles: the Go1's
# shorter leg takes a proportionally shorter step at the same angles). The leg layout: r, half
# the foot's step, 1 + 8 d cm, ANYmal's too (the step a speed needs does not depend on the
# leg: 4 r f is 0.5 m/s at d = 0.5 and 3 Hz). The gains are trained with the rest.
JOINT_INITIAL = {
    "frequency": 3.0,  # Hz, c_nu0
    "frequency_gain": 0.1,  # Hz per (m/s), c_nu1 (> 0 to be trainable)
    "amplitude": (0.05, 0.3) * 4,  # rad, c_R0 of hip and knee of each leg
    "amplitude_gain": (0.2, 0.1) * 4,  # rad per (m/s), c_R1
    "convergence": 20.0,  # 1/s
    "coupling_weight": 10.0,
}
LEG_INITIAL = {
    "frequency": 3.0,  # Hz, c_nu0
    "frequency_gain": 0.1,  # Hz per (m/s), c_nu1
    "amplitude": 0.01,  # m, c_R0
    "amplitude_gain": 0.08,  # m per (m/s), c_R1
    "convergence": 20.0,  # 1/s
    "coupling_weight": 10.0,
}

GO1_GAITS = GaitCPGs(
    legs=("FR", "FL", "RR", "RL"),
    places=("RF", "LF", "RH", "LH"),  # front right, front left, rear right, rear left
    joints=("thigh", "calf"),
    knee_signs=(-1, -1, -1, -1),
    joint_initial=JOINT_INITIAL,
    leg_initial=LEG_INITIAL,
)
