"""The single-leg ANYmal hopper as plain Python data: the one source of both robot files.

The hopper is ANYmal B's right-front leg (:mod:`cpg_actor.robots.anymal_leg`, from
ANYbotics' public description) on a vertical rail: this module adds the rail and the hip
slider, and carries the leg's links as the hopper's files state them (rounded, principal
inertias only); ``docs/hopper.md`` lists each number with its reason. ``mjcf.py``
and ``urdf.py`` turn this data into the MJCF (MuJoCo)
and URDF (PyBullet) files shipped in ``cpg_actor/robots/hopper/assets``; a test checks that both
simulators load the same masses, inertias and joint frames from them.

Frames and sign conventions (world: x forward, y to the robot's left, z up):

* ``rail``: prismatic joint along world +z carrying the hip link. Its position *is* the hip
  height: the height of the hip link frame, which is also the height of the HFE axis.
* ``HFE`` (hip flexion/extension) and ``KFE`` (knee flexion/extension): revolute joints about
  +y (right-hand rule). A positive angle turns the link *backwards* (a leg hanging straight
  down swings towards -x); at HFE = KFE = 0 the thigh hangs straight down.
* Nominal standing pose (legged_gym's ANYmal default) HFE = 0.4 rad, KFE = -0.8 rad: the thigh
  leans 0.4 rad back, so the knee points backwards (ANYmal's front-leg configuration), and the
  shank leans 0.4 rad forward; the foot (sphere centre) is then 0.11 m in front of and
  0.47 m below the HFE axis (13 degrees off the vertical through the hip), knee bent.
"""

from __future__ import annotations

from dataclasses import dataclass

from cpg_actor.robots.anymal_leg import description as leg

Vec3 = tuple[float, float, float]

GRAVITY = leg.GRAVITY
LICENSE_NOTICE = leg.LICENSE_NOTICE  # ANYbotics' notice, in both robot files
RF = (1, -1)  # the leg's signs (sx, sy): the right-front leg

ROBOT_NAME = "anymal_hopper"
JOINT_NAMES = ("HFE", "KFE")  # actuated joints, in action / observation order
RAIL_JOINT = "rail"
NOMINAL_POSE = (leg.NOMINAL_HFE, leg.NOMINAL_KFE)  # rad, HFE and KFE

# Mechanical joint stops, rad (also the bounds of the action space: desired positions): the
# leg's range, nominal pose +-0.9 rad (the leg goes from folded, hip ~0.33 m, to almost
# straight, hip ~0.55 m).
JOINT_LIMITS = {"HFE": (-0.5, 1.3), "KFE": (-1.7, 0.1)}
# Rail stops, m of hip height: a bottom stop (the test stand's) and a top far out of reach.
RAIL_LIMITS = (0.15, 2.0)


@dataclass(frozen=True)
class Link:
    """A rigid link as the hopper's files state it: its inertial properties in its own frame
    (principal axes = frame axes)."""

    name: str
    mass: float  # kg
    com: Vec3  # m
    inertia: Vec3  # kg m^2, diagonal (ixx, iyy, izz) about the COM


@dataclass(frozen=True)
class Joint:
    """A joint: the child frame sits at ``origin`` in the parent frame, same orientation."""

    name: str
    kind: str  # "prismatic", "revolute" or "fixed"
    parent: str
    child: str
    origin: Vec3
    axis: Vec3 = (0.0, 1.0, 0.0)
    limits: tuple[float, float] | None = None


# The leg's links (:data:`cpg_actor.robots.anymal_leg.description.LINKS`) on the right-front
# leg, rounded as docs/hopper.md lists them, products of inertia left out (a test checks they
# round the leg's facts).
LINKS = {
    link.name: link
    for link in (
        Link("hip", 1.42462, (0.0645, 0.0038, -0.0002), (2.430e-3, 2.303e-3, 1.981e-3)),
        Link("thigh", 1.63498, (-0.0039, -0.0542, -0.2146), (1.204e-2, 1.206e-2, 2.494e-3)),
        Link("shank", 0.20720, (0.0308, 0.0046, 0.0009), (2.105e-4, 6.763e-4, 5.450e-4)),
        Link("adapter", 0.14017, (0.0, 0.0, -0.2443), (1.599e-3, 1.599e-3, 5.44e-5)),
    )
}

# the leg's joint origins on the right-front leg
HFE_ORIGIN, KFE_ORIGIN, ADAPTER_ORIGIN = (
    leg.mirrored(origin, *RF) for origin in (leg.HFE_ORIGIN, leg.KFE_ORIGIN, leg.ADAPTER_ORIGIN)
)
JOINTS = (
    Joint("rail", "prismatic", "world", "hip", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), RAIL_LIMITS),
    Joint("HFE", "revolute", "hip", "thigh", HFE_ORIGIN, limits=JOINT_LIMITS["HFE"]),
    Joint("KFE", "revolute", "thigh", "shank", KFE_ORIGIN, limits=JOINT_LIMITS["KFE"]),
    Joint("shank_to_adapter", "fixed", "shank", "adapter", ADAPTER_ORIGIN),
)

# The leg's foot (its contact sphere) on the adapter
FOOT_LINK = "adapter"
FOOT_POINT = leg.FOOT_POINT
FOOT_RADIUS = leg.FOOT_RADIUS
FOOT_CENTER = leg.FOOT_CENTER  # in the adapter frame
FOOT_FRICTION = leg.FOOT_FRICTION

TOTAL_MASS = sum(link.mass for link in LINKS.values())  # 3.40697 kg, all of it moves on the rail

# Visual-only shapes (no collision, no mass): (link, kind, size, from, to) for capsules / boxes.
VISUALS = (
    ("hip", "box", (0.07, 0.06, 0.05), (0.03, -0.02, 0.0), None),
    ("thigh", "capsule", 0.035, (0.0, -0.05, 0.0), (0.0, -0.05, -0.25)),
    ("shank", "capsule", 0.03, (0.0, 0.0, 0.0), (0.1, 0.0, 0.0)),
    ("adapter", "capsule", 0.018, (0.0, 0.0, 0.0), (0.0, 0.0, -0.27)),
)
