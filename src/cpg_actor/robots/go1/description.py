"""The Unitree Go1 quadruped as plain Python data: the one source of its MJCF (``mjcf.py``).

Every number is a fact of the public MJCF description of the Go1 in MuJoCo Menagerie
(``unitree_go1/go1.xml``, derived by Menagerie from Unitree's public URDF,
unitreerobotics/unitree_ros ``go1_description``; BSD-3-Clause, the notice is in
:data:`LICENSE_NOTICE` and in every generated file). No file of either package is included:
the numbers are written here as data and this project generates its own MJCF from them.

Frames (world: x forward, y left, z up). The trunk is the free base. Each leg: the abduction
joint (``<leg>_hip_joint``, about +x) from the trunk to the hip body; the hip flexion
(``<leg>_thigh_joint``) and the knee (``<leg>_calf_joint``) about +y: a positive hip angle turns
the thigh backwards, the knee flexes towards negative angles on every leg. Joint order
(actions, observations): FR, FL, RR, RL, each abduction, hip, knee. The legs differ in the
signs of x and y of their offsets, written here as ``(sx, sy)``: FR (+, -), FL (+, +),
RR (-, -), RL (-, +); the per-leg inertia orientations are Menagerie's, leg by leg.

Inertias are principal moments with the orientation of their principal axes (MuJoCo's
``diaginertia`` and ``quat``). Collision shapes are primitives (the meshes are visual and left
out); simplifications, with reasons: the head's small boxes and capsules (the README gives no
sizes) and the second, smaller hip cylinder are left out, the hip cylinder sits at the hip
frame's origin; every collision shape touches the ground only (no self-collision: the task ends
when the trunk touches the ground, and legs crossing is not a gait this task asks for).
"""

from __future__ import annotations

from dataclasses import dataclass

from cpg_actor.robots.common.notice import bsd_3_clause

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]  # w x y z

ROBOT_NAME = "go1"
GRAVITY = 9.81
LEGS = ("FR", "FL", "RR", "RL")
LEG_SIGNS = {"FR": (1, -1), "FL": (1, 1), "RR": (-1, -1), "RL": (-1, 1)}
JOINT_KINDS = ("hip", "thigh", "calf")  # abduction, hip flexion, knee (Menagerie's names)
JOINT_NAMES = tuple(f"{leg}_{kind}_joint" for leg in LEGS for kind in JOINT_KINDS)
JOINT_AXES = {"hip": (1.0, 0.0, 0.0), "thigh": (0.0, 1.0, 0.0), "calf": (0.0, 1.0, 0.0)}

# the joints' ranges (rad), torque limits (N m) and passive dynamics, per joint kind
JOINT_RANGES = {"hip": (-0.863, 0.863), "thigh": (-0.686, 4.501), "calf": (-2.818, -0.888)}
TORQUE_LIMITS = {"hip": 23.7, "thigh": 23.7, "calf": 35.55}
DAMPING = {"hip": 1.0, "thigh": 2.0, "calf": 2.0}  # N m s / rad
ARMATURE = 0.01  # kg m^2, each joint (the reflected rotor inertia)
FRICTION_LOSS = 0.2  # N m, each joint

# Nominal standing pose (Menagerie's "home" keyframe): abduction 0, hip 0.9, knee -1.8, the
# trunk at z = 0.27.
NOMINAL_POSE = (0.0, 0.9, -1.8) * 4
HOME_HEIGHT = 0.27  # m
# Action bounds (rad): ANYmal B's choice (robots/anymal/description.py), +-0.6 rad of abduction
# and +-0.9 rad of hip and knee around the nominal pose, all inside the joint ranges. The full
# ranges (the hip's spans 5.2 rad) would make an action's scale a poor fit for a walking gait.
ACTION_RANGE = {"hip": 0.6, "thigh": 0.9, "calf": 0.9}
ACTION_LIMITS = {
    name: (pose - ACTION_RANGE[name.split("_")[1]], pose + ACTION_RANGE[name.split("_")[1]])
    for name, pose in zip(JOINT_NAMES, NOMINAL_POSE, strict=True)
}


@dataclass(frozen=True)
class Body:
    """A rigid body: its mass, COM and principal inertia (with its axes) in the body's frame."""

    name: str
    mass: float  # kg
    com: Vec3  # m, in the body frame
    inertia: Vec3  # kg m^2, principal moments
    axes: Quat  # orientation of the principal axes in the body frame


TRUNK = Body(
    "trunk",
    5.204,
    (0.0223, 0.002, -0.0005),
    (0.0716565, 0.0630105, 0.0168101),
    (-0.00342088, 0.705204, 0.000106698, 0.708996),
)
HIP_ORIGIN = (0.1881, 0.04675, 0.0)  # FL; the others by (sx, sy)
THIGH_ORIGIN_Y = 0.08  # m, the hip flexion axis from the abduction axis, outwards
KNEE_ORIGIN = (0.0, 0.0, -0.213)  # in the thigh frame
FOOT_CENTER = (0.0, 0.0, -0.213)  # in the calf frame
FOOT_RADIUS = 0.023

HIP_AXES = {
    "FR": (0.507341, 0.514169, 0.495027, 0.482891),
    "FL": (0.482891, 0.495027, 0.514169, 0.507341),
    "RR": (0.495027, 0.482891, 0.507341, 0.514169),
    "RL": (0.514169, 0.507341, 0.482891, 0.495027),
}
THIGH_AXES = {  # right legs (sy = -1) and left legs (sy = +1)
    -1: (0.65243, -0.0272313, 0.0775126, 0.753383),
    1: (0.753383, 0.0775126, -0.0272313, 0.65243),
}


def _leg_bodies(leg: str) -> list[tuple[Body, Vec3, str]]:
    """The leg's bodies, each with its origin in its parent and the joint that carries it."""
    sx, sy = LEG_SIGNS[leg]
    return [
        (Body(f"{leg}_hip", 0.68, (-0.0049166 * sx, -0.00762615 * sy, -8.865e-05),
              (0.000734064, 0.000468438, 0.000398719), HIP_AXES[leg]),
         (HIP_ORIGIN[0] * sx, HIP_ORIGIN[1] * sy, 0.0), f"{leg}_hip_joint"),
        (Body(f"{leg}_thigh", 1.009, (-0.00304722, -0.019315 * sy, -0.0305004),
              (0.00478717, 0.00460903, 0.000709268), THIGH_AXES[sy]),
         (0.0, THIGH_ORIGIN_Y * sy, 0.0), f"{leg}_thigh_joint"),
        (Body(f"{leg}_calf", 0.195862, (0.00429862, 0.000976676, -0.146197),
              (0.00149767, 0.00148468, 3.58427e-05), (0.691246, 0.00357467, 0.00511118, 0.722592)),
         KNEE_ORIGIN, f"{leg}_calf_joint"),
    ]  # fmt: skip


LEG_BODIES = {leg: _leg_bodies(leg) for leg in LEGS}
LEG_MASS = sum(body.mass for body, _, _ in LEG_BODIES["FL"])  # 1.884862 kg
TOTAL_MASS = TRUNK.mass + 4 * LEG_MASS  # 12.743448 kg

# Collision primitives (MJCF geom type, size, and placement: "pos" or "fromto"; m), in each
# body's frame; y of the leg shapes is mirrored with the leg.
TRUNK_GEOMS = (
    ("box", (0.125, 0.04, 0.057), {"pos": (0.0, 0.0, 0.0)}),
    ("cylinder", (0.058,), {"fromto": (-0.125, 0.04, 0.0, 0.125, 0.04, 0.0)}),
    ("cylinder", (0.058,), {"fromto": (-0.125, -0.04, 0.0, 0.125, -0.04, 0.0)}),
)
HIP_GEOMS = (("cylinder", (0.046,), {"fromto": (0.0, -0.02, 0.0, 0.0, 0.02, 0.0)}),)
THIGH_GEOMS = (
    ("capsule", (0.015,), {"fromto": (-0.02, 0.0, 0.0, -0.02, 0.0, -0.16)}),
    ("capsule", (0.015,), {"fromto": (0.0, 0.0, 0.0, -0.02, 0.0, -0.1)}),
    ("capsule", (0.015,), {"fromto": (-0.02, 0.0, -0.16, 0.0, 0.0, -0.2)}),
)
CALF_GEOMS = (
    ("capsule", (0.01,), {"fromto": (0.0, 0.0, 0.0, 0.02, 0.0, -0.13)}),
    ("capsule", (0.01,), {"fromto": (0.02, 0.0, -0.13, 0.0, 0.0, -0.2)}),
)
# the box around the trunk's shapes (centre, half sizes; the trunk is the base): the MJX env's
# stand-in for the touch sensor, and the touch sensor's site (2 mm larger)
BASE_BOX = ((0.0, 0.0, 0.0), (0.125, 0.098, 0.058))

# contact: the feet's (sliding, torsional, rolling friction; condim 6; soft, Menagerie's solimp
# to approximate rubber), the other shapes' sliding friction
FOOT_FRICTION = 0.8
FOOT_SPIN_ROLL = (0.02, 0.01)
FOOT_CONDIM = 6
FOOT_SOLIMP = (0.015, 1.0, 0.031)
GEOM_FRICTION = 0.6

LICENSE_NOTICE = bsd_3_clause(
    "Robot data from the Unitree Go1 description of MuJoCo Menagerie (unitree_go1/go1.xml, "
    "derived\nfrom Unitree Robotics' public URDF, unitree_ros/robots/go1_description):",
    'Copyright (c) 2016-2022 HangZhou YuShu TECHNOLOGY CO.,LTD. ("Unitree Robotics")\n'
    "All rights reserved.",
)
