"""The ANYmal B quadruped as plain Python data: the one source of its MJCF (``mjcf.py``).

Every number is a fact of ANYbotics' public ANYmal B description (``anymal.urdf`` of
ANYbotics/anymal_b_simple_description, commit 988b5df, BSD-3-Clause; the notice is in
:data:`LICENSE_NOTICE` and in every generated file). The legs are the hopper's leg
(:mod:`cpg_actor.robots.hopper.description`, the right-front leg) mirrored: the URDF's four legs
differ only in the signs of x and y, written here as ``(sx, sy)``: LF (+, +), RF (+, -),
LH (-, +), RH (-, -). ``docs/quadruped.md`` lists each number with its reason.

Frames (world: x forward, y left, z up). The base link's frame is the body frame; its inertial
frame is the URDF's ``base_inertia`` (fixed to it). Each leg: HAA (hip abduction/adduction,
about +x) from the base to the hip link; HFE (hip flexion/extension) and KFE (knee) about +y, as
on the hopper: a positive HFE angle turns the thigh backwards. Joint order (actions,
observations): LF, RF, LH, RH, each HAA, HFE, KFE.

Simplifications, with reasons: link inertias keep the URDF's products of inertia
(``fullinertia``); collision is the feet (the hopper's spheres) and one box for the base (the
URDF's main body box), the rest of the URDF's collision shapes (actuator cylinders, belly
bumps, thigh and shank boxes) are left out: the task ends when the base touches the ground.
"""

from __future__ import annotations

from dataclasses import dataclass

from cpg_actor.robots.hopper import description as hopper

Vec3 = tuple[float, float, float]
Inertia = tuple[float, float, float, float, float, float]  # ixx iyy izz ixy ixz iyz (MuJoCo)

ROBOT_NAME = "anymal_b"
GRAVITY = hopper.GRAVITY
LEGS = ("LF", "RF", "LH", "RH")
LEG_SIGNS = {"LF": (1, 1), "RF": (1, -1), "LH": (-1, 1), "RH": (-1, -1)}
JOINT_KINDS = ("HAA", "HFE", "KFE")
JOINT_NAMES = tuple(f"{leg}_{kind}" for leg in LEGS for kind in JOINT_KINDS)

# Nominal standing pose (legged_gym's ANYmal default): HAA 0, front legs HFE 0.4 / KFE -0.8
# (knees backwards, as the hopper), hind legs mirrored front-to-back, HFE -0.4 / KFE 0.8
# (knees forwards): ANYmal's "X" configuration.
NOMINAL_POSE = tuple(
    {"HAA": 0.0, "HFE": 0.4 * sx, "KFE": -0.8 * sx}[kind]
    for leg in LEGS
    for sx in (LEG_SIGNS[leg][0],)
    for kind in JOINT_KINDS
)
# Joint stops (also the action bounds), rad. The URDF gives +-9.42 (no mechanical stop); these
# are the hopper's +-0.9 rad around the nominal pose for HFE and KFE, and +-0.6 rad for HAA
# (enough to place a foot 0.3 m sideways, not enough to fold a leg under the body).
HAA_RANGE = 0.6
LEG_RANGE = 0.9
JOINT_LIMITS = {
    name: (pose - (HAA_RANGE if name.endswith("HAA") else LEG_RANGE),
           pose + (HAA_RANGE if name.endswith("HAA") else LEG_RANGE))
    for name, pose in zip(JOINT_NAMES, NOMINAL_POSE, strict=True)
}  # fmt: skip


@dataclass(frozen=True)
class Body:
    """A rigid body: its mass, COM and inertia (about the COM, in the body's frame)."""

    name: str
    mass: float  # kg
    com: Vec3  # m, in the body frame
    inertia: Inertia  # kg m^2


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


def _leg_bodies(leg: str) -> list[tuple[Body, Vec3, str | None]]:
    """The leg's bodies, each with its origin in its parent and the joint that carries it
    (``None``: fixed). Numbers of the URDF's LF leg, signs by (sx, sy)."""
    sx, sy = LEG_SIGNS[leg]
    return [
        (Body(f"{leg}_HIP", 1.42462064, (0.064516258147 * sx, -0.003787101702 * sy,
                                          -0.000152184388),
              (0.00243023349564, 0.00230257239103, 0.0019806759227,
               -1.53023971e-05 * sx * sy, -2.1819095354e-05 * sx, 2.6473021273e-05 * sy)),
         (HAA_ORIGIN[0] * sx, HAA_ORIGIN[1] * sy, 0.0), f"{leg}_HAA"),
        (Body(f"{leg}_THIGH", 1.634976467, (-0.003897968082 * sx, 0.054226618537 * sy,
                                             -0.214583373795),
              (0.0120367944369, 0.0120643637939, 0.00249422574881,
               6.762065206e-05 * sx * sy, 0.000287806340448 * sx, -0.00140610131218 * sy)),
         (0.0635 * sx, 0.041 * sy, 0.0), f"{leg}_HFE"),
        (Body(f"{leg}_SHANK", 0.207204302, (0.030816858139 * sx, -0.004617229294 * sy,
                                             0.000893125713),
              (0.0002104880248, 0.000676270210023, 0.000545032674924,
               -5.6750980345e-05 * sx * sy, 1.0127699391e-05 * sx, -8.22869024e-07 * sy)),
         (0.0, 0.109 * sy, -0.25), f"{leg}_KFE"),
        (Body(f"{leg}_ADAPTER", 0.140170767, (0.0, 0.0, -0.244345749188),
              (0.00159938741862, 0.00159938741932, 5.4423177329e-05, 0.0, 0.0, 0.0)),
         (0.1 * sx, -0.02 * sy, 0.0), None),
    ]  # fmt: skip


LEG_BODIES = {leg: _leg_bodies(leg) for leg in LEGS}
JOINT_AXES = {"HAA": (1.0, 0.0, 0.0), "HFE": (0.0, 1.0, 0.0), "KFE": (0.0, 1.0, 0.0)}

# The foot: the hopper's contact sphere on each adapter (centre 0.298 m below the adapter frame).
FOOT_RADIUS = hopper.FOOT_RADIUS
FOOT_CENTER = hopper.FOOT_CENTER
FOOT_FRICTION = hopper.FOOT_FRICTION

LEG_MASS = sum(body.mass for body, _, _ in LEG_BODIES["LF"])  # 3.40697 kg, the hopper's
TOTAL_MASS = BASE.mass + 4 * LEG_MASS  # 30.4214 kg

LICENSE_NOTICE = """\
Robot data from ANYbotics' ANYmal B description (anymal_b_simple_description, urdf/anymal.urdf):
Copyright 2019, ANYbotics AG.

Redistribution and use in source and binary forms, with or without
modification, are permitted provided that the following conditions
are met:

1. Redistributions of source code must retain the above copyright
   notice, this list of conditions and the following disclaimer.

2. Redistributions in binary form must reproduce the above copyright
   notice, this list of conditions and the following disclaimer in
   the documentation and/or other materials provided with the
   distribution.

3. Neither the name of the copyright holder nor the names of its
   contributors may be used to endorse or promote products derived
   from this software without specific prior written permission.

THIS SOFTWARE IS PROVIDED BY THE COPYRIGHT HOLDERS AND CONTRIBUTORS
"AS IS" AND ANY EXPRESS OR IMPLIED WARRANTIES, INCLUDING, BUT NOT
LIMITED TO, THE IMPLIED WARRANTIES OF MERCHANTABILITY AND FITNESS FOR
A PARTICULAR PURPOSE ARE DISCLAIMED. IN NO EVENT SHALL THE COPYRIGHT
HOLDER OR CONTRIBUTORS BE LIABLE FOR ANY DIRECT, INDIRECT, INCIDENTAL,
SPECIAL, EXEMPLARY, OR CONSEQUENTIAL DAMAGES (INCLUDING, BUT NOT
LIMITED TO, PROCUREMENT OF SUBSTITUTE GOODS OR SERVICES; LOSS OF USE,
DATA, OR PROFITS; OR BUSINESS INTERRUPTION) HOWEVER CAUSED AND ON ANY
THEORY OF LIABILITY, WHETHER IN CONTRACT, STRICT LIABILITY, OR TORT
(INCLUDING NEGLIGENCE OR OTHERWISE) ARISING IN ANY WAY OUT OF THE USE
OF THIS SOFTWARE, EVEN IF ADVISED OF THE POSSIBILITY OF SUCH DAMAGE.
"""
