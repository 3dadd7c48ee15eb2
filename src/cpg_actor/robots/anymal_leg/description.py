"""ANYmal B's leg as plain Python data: the facts the hopper (one leg on a rail) and ANYmal B
(four legs on a base) share.

Every number is a fact of ANYbotics' public ANYmal B description (``anymal.urdf`` of
ANYbotics/anymal_b_simple_description, BSD-3-Clause; the notice is :data:`LICENSE_NOTICE`, in
every file generated from them), written for the left-front (LF) leg. The URDF's four legs
differ only in the signs of x and y, ``(sx, sy)``: LF (+, +), RF (+, -), LH (-, +), RH (-, -);
:func:`mirrored` and :meth:`Link.mirrored` apply them. The hopper is the right-front leg.

The leg, from the body it hangs on: the hip link, the HFE joint (hip flexion/extension, about
+y) to the thigh, the KFE joint (knee, about +y) to the shank, the adapter fixed to the shank,
and the foot: a contact sphere on the adapter. A positive HFE angle turns the thigh backwards.
"""

from __future__ import annotations

from dataclasses import dataclass

from cpg_actor.robots.common.notice import bsd_3_clause

Vec3 = tuple[float, float, float]
Inertia = tuple[float, float, float, float, float, float]  # ixx iyy izz ixy ixz iyz (MuJoCo)

LICENSE_NOTICE = bsd_3_clause(
    "Robot data from ANYbotics' ANYmal B description (anymal_b_simple_description, "
    "urdf/anymal.urdf):",
    "Copyright 2019, ANYbotics AG.",
)

GRAVITY = 9.81  # m/s^2, every simulator of the project

# Nominal standing pose of a front leg (legged_gym's ANYmal default), rad: the thigh leans
# 0.4 rad back, the knee points backwards. Hind legs are the front legs mirrored front-to-back.
NOMINAL_HFE, NOMINAL_KFE = 0.4, -0.8
# Joint stops around the nominal pose, rad (the URDF has none): wide enough for a squat-and-
# extend hop, narrow enough that a random policy cannot fold the foot above the hip.
LEG_RANGE = 0.9


def mirrored(v: Vec3, sx: int, sy: int) -> Vec3:
    """An LF-leg vector for the leg with signs ``(sx, sy)`` (``+ 0.0``: no negative zeros)."""
    return (v[0] * sx + 0.0, v[1] * sy + 0.0, v[2])


@dataclass(frozen=True)
class Link:
    """A rigid link: mass, COM and inertia about the COM, in its own frame (LF leg)."""

    name: str
    mass: float  # kg
    com: Vec3  # m
    inertia: Inertia  # kg m^2

    def mirrored(self, sx: int, sy: int, name: str | None = None) -> Link:
        """The same link on the leg with signs ``(sx, sy)``: a reflection flips the products
        of inertia that mix a flipped axis with one that is not."""
        ixx, iyy, izz, ixy, ixz, iyz = self.inertia
        inertia = (ixx, iyy, izz, ixy * sx * sy + 0.0, ixz * sx + 0.0, iyz * sy + 0.0)
        return Link(name or self.name, self.mass, mirrored(self.com, sx, sy), inertia)


HIP = Link(
    "HIP", 1.42462064, (0.064516258147, -0.003787101702, -0.000152184388),
    (0.00243023349564, 0.00230257239103, 0.0019806759227,
     -1.53023971e-05, -2.1819095354e-05, 2.6473021273e-05),
)  # fmt: skip
THIGH = Link(
    "THIGH", 1.634976467, (-0.003897968082, 0.054226618537, -0.214583373795),
    (0.0120367944369, 0.0120643637939, 0.00249422574881,
     6.762065206e-05, 0.000287806340448, -0.00140610131218),
)  # fmt: skip
SHANK = Link(
    "SHANK", 0.207204302, (0.030816858139, -0.004617229294, 0.000893125713),
    (0.0002104880248, 0.000676270210023, 0.000545032674924,
     -5.6750980345e-05, 1.0127699391e-05, -8.22869024e-07),
)  # fmt: skip
ADAPTER = Link(
    "ADAPTER", 0.140170767, (0.0, 0.0, -0.244345749188),
    (0.00159938741862, 0.00159938741932, 5.4423177329e-05, 0.0, 0.0, 0.0),
)  # fmt: skip
LINKS = (HIP, THIGH, SHANK, ADAPTER)  # from the body down
LEG_MASS = sum(link.mass for link in LINKS)  # 3.40697 kg

# Where each link sits in the one above it (LF leg, m; same orientation)
HFE_ORIGIN = (0.0635, 0.041, 0.0)  # the thigh (HFE axis) in the hip frame
KFE_ORIGIN = (0.0, 0.109, -0.25)  # the shank (KFE axis) in the thigh frame
ADAPTER_ORIGIN = (0.1, -0.02, 0.0)  # the adapter in the shank frame (fixed)

# The foot: a point of the adapter at (0, 0, -0.32125); the contact sphere is centred 0.02325 m
# above it. Foot position / velocity / height everywhere in this package refer to the sphere.
FOOT_POINT = (0.0, 0.0, -0.32125)
FOOT_RADIUS = 0.031
FOOT_CENTER = (0.0, 0.0, -0.32125 + 0.02325)  # in the adapter frame
FOOT_FRICTION = 0.8
