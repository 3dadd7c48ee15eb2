"""MJCF (MuJoCo) text of the Unitree Go1, generated from :mod:`description`.

As ANYmal's (:mod:`cpg_actor.robots.anymal.mjcf`): Euler integrator, elliptic friction cone with
``impratio`` 100, and on every joint a ``dcmotor`` actuator that is the project's actuator law
(:mod:`cpg_actor.robots.common.actuator`: PD on the desired position, the torque-speed line, the
torque clip, here with the Go1's per-joint constants), so MuJoCo runs it at every substep. The
joints carry the description's passive damping, armature and friction loss. Collision shapes are
the description's primitives; each touches the ground only. The feet are Menagerie's soft
rubber spheres (condim 6, ``solimp`` 0.015 1 0.031). The shipped file's timestep and friction
are the defaults: the env sets them from its config
(:func:`cpg_actor.robots.common.mjcf.simulated_mjcf` writes them in). The document around the
trunk and the legs is every quadruped's (:mod:`cpg_actor.robots.common.quadruped.mjcf`).
"""

from __future__ import annotations

from pathlib import Path

from cpg_actor.robots.common.mjcf import exact
from cpg_actor.robots.common.mjcf import numbers as _v
from cpg_actor.robots.common.notice import generated_comment
from cpg_actor.robots.common.quadruped.mjcf import INDENT, quadruped_mjcf
from cpg_actor.robots.go1 import description as robot

MJCF_PATH = Path(__file__).resolve().parent / "assets" / f"{robot.ROBOT_NAME}.xml"
SOURCES = ("cpg_actor/robots/go1/description.py",)
COLLISION = f'contype="0" conaffinity="1" condim="3" friction="{robot.GEOM_FRICTION:.6g}"'


def _inertial(body: robot.Body) -> str:
    return (f'<inertial pos="{_v(body.com)}" quat="{_v(body.axes)}" mass="{body.mass:.12g}" '
            f'diaginertia="{_v(body.inertia)}"/>')  # fmt: skip


def _geoms(shapes, sy: int, pad: str, rgba: str) -> list[str]:
    """Collision primitives (``description``'s tuples), y mirrored by ``sy``."""
    lines = []
    for kind, size, place in shapes:
        (key, values), = place.items()  # fmt: skip
        values = [v * sy if i % 3 == 1 else v for i, v in enumerate(values)]
        lines.append(f'{pad}<geom type="{kind}" size="{_v(size)}" {key}="{_v(values)}" '
                     f'{COLLISION} rgba="{rgba}"/>')  # fmt: skip
    return lines


def _joint(name: str, pad: str) -> str:
    kind = name.split("_")[1]
    lo, hi = robot.JOINT_RANGES[kind]
    return (f'{pad}<joint name="{name}" type="hinge" axis="{_v(robot.JOINT_AXES[kind])}" '
            f'range="{lo:.6g} {hi:.6g}" damping="{robot.DAMPING[kind]:.6g}" '
            f'armature="{robot.ARMATURE:.6g}" '
            f'frictionloss="{robot.FRICTION_LOSS:.6g}"/>')  # fmt: skip


def _foot(leg: str, pad: str, friction: float) -> list[str]:
    spin, roll = robot.FOOT_SPIN_ROLL
    return [
        f'{pad}<geom name="{leg}_foot" class="foot" type="sphere" size="{robot.FOOT_RADIUS:.6g}" '
        f'pos="{_v(robot.FOOT_CENTER)}" contype="0" condim="{robot.FOOT_CONDIM}" '
        f'friction="{exact(friction)} {spin:.6g} {roll:.6g}" solref="0.02 1" '
        f'solimp="{_v(robot.FOOT_SOLIMP)}"/>',
        f'{pad}<site name="{leg}_foot" pos="{_v(robot.FOOT_CENTER)}" size="0.005"/>',
    ]


def _leg(leg: str, foot_friction: float) -> list[str]:
    """The nested bodies of one leg, from the hip to the calf with its foot."""
    sy = robot.LEG_SIGNS[leg][1]
    shapes = {"hip": robot.HIP_GEOMS, "thigh": robot.THIGH_GEOMS, "calf": robot.CALF_GEOMS}
    lines, closes = [], []
    for depth, (body, origin, joint) in enumerate(robot.LEG_BODIES[leg]):
        pad = INDENT + "  " * depth
        inner = pad + "  "
        kind = body.name.split("_")[1]
        lines.append(f'{pad}<body name="{body.name}" pos="{_v(origin)}">')
        lines.append(inner + _inertial(body))
        lines.append(_joint(joint, inner))
        lines += _geoms(shapes[kind], sy, inner, "0.85 0.35 0.1 1")
        if kind == "calf":
            lines += _foot(leg, inner, foot_friction)
        closes.append(f"{pad}</body>")
    return lines + closes[::-1]


def mjcf_text(
    actuator=None,
    torque_control: bool = False,
    timestep: float = 0.002,
    foot_friction: float = robot.FOOT_FRICTION,
) -> str:
    """The complete MJCF document (``actuator``: the law's constants, default the default
    :class:`~cpg_actor.robots.go1.config.Go1Config`'s; ``torque_control``: plain motors and no
    sensors, for MJX; the physics ``timestep``; ``foot_friction``: the feet's and the ground's
    sliding friction)."""
    from cpg_actor.robots.common.actuator import Actuator
    from cpg_actor.robots.go1.config import Go1Config

    return quadruped_mjcf(
        generated_comment(SOURCES, robot.LICENSE_NOTICE),
        robot.ROBOT_NAME,
        base="trunk",
        base_height=robot.HOME_HEIGHT,
        base_lines=[
            INDENT + _inertial(robot.TRUNK),
            *_geoms(robot.TRUNK_GEOMS, 1, INDENT, "0.3 0.3 0.35 1"),
        ],
        base_box=robot.BASE_BOX,
        leg_lines=[line for leg in robot.LEGS for line in _leg(leg, foot_friction)],
        legs=robot.LEGS,
        joint_names=robot.JOINT_NAMES,
        actuator=actuator or Actuator.from_config(Go1Config()),
        torque_control=torque_control,
        timestep=timestep,
        gravity=robot.GRAVITY,
        foot_friction=foot_friction,
    )


def extra_assets() -> dict[Path, str]:
    """The other shipped models of the Go1: :mod:`cpg_actor.robots.go1.variant`'s."""
    from cpg_actor.robots.go1.variant import variant_assets

    return variant_assets()
