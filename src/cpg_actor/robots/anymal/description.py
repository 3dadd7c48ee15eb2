"""The ANYmal B quadruped as plain Python data: the one source of its MJCF (``mjcf.py``).

Every number is a fact of ANYbotics' public ANYmal B description (``anymal.urdf`` of
ANYbotics/anymal_b_simple_description, commit 988b5df, BSD-3-Clause; the notice is
:data:`LICENSE_NOTICE`, in every generated file). This module adds the base and the HAA
joints to four copies of the leg (:mod:`cpg_actor.robots.anymal_leg`, shared with the hopper)
mirrored: the URDF's four legs differ only in the signs of x and y, written here as
``(sx, sy)``: LF (+, +), RF (+, -), LH (-, +), RH (-, -). ``docs/quadruped.md`` lists each
number with its reason.

Frames (world: x forward, y left, z up). The base link's frame is the body frame; its inertial
frame is the URDF's ``base_inertia`` (fixed to it). Each leg: HAA (hip abduction/adduction,
about +x) from the base to the hip link; HFE (hip flexion/extension) and KFE (knee) about +y, as
on the hopper: a positive HFE angle turns the thigh backwards. Joint order (actions,
observations): LF, RF, LH, RH, each HAA, HFE, KFE.

Simplifications, with reasons: link inertias keep the URDF's products of inertia
(``fullinertia``); collision is the feet (the leg's spheres) and one box for the base (the
URDF's main body box), the rest of the URDF's collision shapes (actuator cylinders, belly
bumps, thigh and shank boxes) are left out: the task ends when the base touches the ground.
"""

from __future__ import annotations

from cpg_actor.robots.anymal_leg import description as anymal_leg

Vec3 = anymal_leg.Vec3
Inertia = anymal_leg.Inertia

ROBOT_NAME = "anymal_b"
GRAVITY = anymal_leg.GRAVITY
LEGS = ("LF", "RF", "LH", "RH")
LEG_SIGNS = {"LF": (1, 1), "RF": (1, -1), "LH": (-1, 1), "RH": (-1, -1)}
JOINT_KINDS = ("HAA", "HFE", "KFE")
JOINT_NAMES = tuple(f"{leg}_{kind}" for leg in LEGS for kind in JOINT_KINDS)

# Nominal standing pose (legged_gym's ANYmal default): HAA 0, front legs HFE 0.4 / KFE -0.8
# (knees backwards, the leg's), hind legs mirrored front-to-back, HFE -0.4 / KFE 0.8
# (knees forwards): ANYmal's "X" configuration.
NOMINAL_POSE = tuple(
    {"HAA": 0.0, "HFE": anymal_leg.NOMINAL_HFE * sx, "KFE": anymal_leg.NOMINAL_KFE * sx}[kind]
    for leg in LEGS
    for sx in (LEG_SIGNS[leg][0],)
    for kind in JOINT_KINDS
)
# Joint stops (also the action bounds), rad. The URDF gives +-9.42 (no mechanical stop); these
# are the leg's +-0.9 rad around the nominal pose for HFE and KFE, and +-0.6 rad for HAA
# (enough to place a foot 0.3 m sideways, not enough to fold a leg under the body).
HAA_RANGE = 0.6
LEG_RANGE = anymal_leg.LEG_RANGE
JOINT_LIMITS = {
    name: (pose - (HAA_RANGE if name.endswith("HAA") else LEG_RANGE),
           pose + (HAA_RANGE if name.endswith("HAA") else LEG_RANGE))
    for name, pose in zip(JOINT_NAMES, NOMINAL_POSE, strict=True)
}  # fmt: skip
ACTION_LIMITS = JOINT_LIMITS  # the joint stops are the action bounds


Body = anymal_leg.Link  # a rigid body: mass, COM and inertia about the COM, in the body's frame

# The base: the URDF's base_inertia link (fixed to base at the origin).
BASE = Body(
    "base",
    16.793507758,
    (-0.001960558279, -0.001413217745, 0.050207125344),
    (0.217391101503, 0.639432546734, 0.62414077654,
     -0.00132873239126, -0.00228200226173, -0.00138078263145),
)  # fmt: skip
BASE_BOX = ((0.0, 0.0, 0.08), (0.531 / 2, 0.27 / 2, 0.24 / 2))  # centre, half sizes (m)
HAA_ORIGIN = (0.277, 0.116, 0.0)  # LF; the others by (sx, sy)


def _leg_bodies(name: str) -> list[tuple[Body, Vec3, str | None]]:
    """The leg's bodies, each with its origin in its parent and the joint that carries it
    (``None``: fixed): the base's HAA joint, then the leg's links mirrored by (sx, sy)."""
    sx, sy = LEG_SIGNS[name]
    hip, thigh, shank, adapter = (
        link.mirrored(sx, sy, f"{name}_{link.name}") for link in anymal_leg.LINKS
    )
    return [
        (hip, anymal_leg.mirrored(HAA_ORIGIN, sx, sy), f"{name}_HAA"),
        (thigh, anymal_leg.mirrored(anymal_leg.HFE_ORIGIN, sx, sy), f"{name}_HFE"),
        (shank, anymal_leg.mirrored(anymal_leg.KFE_ORIGIN, sx, sy), f"{name}_KFE"),
        (adapter, anymal_leg.mirrored(anymal_leg.ADAPTER_ORIGIN, sx, sy), None),
    ]


LEG_BODIES = {leg: _leg_bodies(leg) for leg in LEGS}
JOINT_AXES = {"HAA": (1.0, 0.0, 0.0), "HFE": (0.0, 1.0, 0.0), "KFE": (0.0, 1.0, 0.0)}

# The foot: the leg's contact sphere on each adapter (centre 0.298 m below the adapter frame).
FOOT_RADIUS = anymal_leg.FOOT_RADIUS
FOOT_CENTER = anymal_leg.FOOT_CENTER
FOOT_FRICTION = anymal_leg.FOOT_FRICTION

LEG_MASS = anymal_leg.LEG_MASS  # 3.40697 kg
TOTAL_MASS = BASE.mass + 4 * LEG_MASS  # 30.4214 kg

LICENSE_NOTICE = anymal_leg.LICENSE_NOTICE  # ANYbotics' notice, of the leg and the base
