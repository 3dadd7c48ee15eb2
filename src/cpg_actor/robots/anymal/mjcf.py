"""MJCF (MuJoCo) text of the ANYmal B quadruped, generated from :mod:`description`.

As the hopper's (:mod:`cpg_actor.robots.hopper.mjcf`): Euler integrator, elliptic friction cone
with ``impratio`` 100 (a standing foot sticks instead of creeping), the feet's soft contact
(``solref`` 0.005), and on every joint a ``dcmotor`` actuator that is the actuator law of
:mod:`cpg_actor.robots.common.actuator` (PD on the desired position, the 15 rad/s torque-speed line,
the 40 N m clip), so MuJoCo runs it at every substep. The base is a free body; its box and the
four foot spheres are the only collision shapes. The shipped file's timestep and friction are
the defaults: the env sets ``opt.timestep`` and the friction from its config
(:func:`cpg_actor.robots.common.mjcf.simulated_mjcf` writes them in). The document around the
base and the legs is every quadruped's (:mod:`cpg_actor.robots.common.quadruped.mjcf`).
"""

from __future__ import annotations

from pathlib import Path

from cpg_actor.robots.anymal import description as robot
from cpg_actor.robots.common.mjcf import numbers as _v
from cpg_actor.robots.common.notice import generated_comment
from cpg_actor.robots.common.quadruped.mjcf import INDENT, quadruped_mjcf

MJCF_PATH = Path(__file__).resolve().parent / "assets" / f"{robot.ROBOT_NAME}.xml"
SOURCES = ("cpg_actor/robots/anymal/description.py", "cpg_actor/robots/anymal_leg/description.py")


def _inertial(body: robot.Body) -> str:
    return (
        f'<inertial pos="{_v(body.com)}" mass="{body.mass:.12g}" fullinertia="{_v(body.inertia)}"/>'
    )


def _leg(leg: str) -> list[str]:
    """The nested bodies of one leg, from the hip to the adapter with its foot."""
    lines, closes = [], []
    for depth, (body, origin, joint) in enumerate(robot.LEG_BODIES[leg]):
        pad = INDENT + "  " * depth
        lines.append(f'{pad}<body name="{body.name}" pos="{_v(origin)}">')
        inner = pad + "  "
        lines.append(inner + _inertial(body))
        if joint is not None:
            lo, hi = robot.JOINT_LIMITS[joint]
            axis = robot.JOINT_AXES[joint.split("_")[1]]
            lines.append(
                f'{inner}<joint name="{joint}" type="hinge" axis="{_v(axis)}" '
                f'range="{lo:.6g} {hi:.6g}"/>'
            )
        if body.name.endswith("_THIGH"):
            lines.append(f'{inner}<geom class="visual" type="capsule" size="0.035" '
                         f'fromto="0 0 0 0 0 -0.25"/>')  # fmt: skip
        if body.name.endswith("_ADAPTER"):
            lines.append(f'{inner}<geom class="visual" type="capsule" size="0.018" '
                         f'fromto="0 0 0 0 0 -0.27"/>')  # fmt: skip
            lines.append(
                f'{inner}<geom name="{leg}_foot" class="foot" type="sphere" '
                f'size="{robot.FOOT_RADIUS:.6g}" pos="{_v(robot.FOOT_CENTER)}"/>'
            )
            lines.append(
                f'{inner}<site name="{leg}_foot" pos="{_v(robot.FOOT_CENTER)}" size="0.005"/>'
            )
        closes.append(f"{pad}</body>")
    return lines + closes[::-1]


def mjcf_text(
    actuator=None,
    torque_control: bool = False,
    timestep: float = 0.002,
    foot_friction: float = robot.FOOT_FRICTION,
) -> str:
    """The complete MJCF document (``actuator``: the law's constants, default the default
    :class:`~cpg_actor.robots.common.quadruped.config.QuadrupedConfig`'s; ``torque_control``:
    plain motors and no sensors, for MJX; the physics ``timestep``; ``foot_friction``: the
    feet's and the ground's)."""
    from cpg_actor.robots.common.actuator import Actuator
    from cpg_actor.robots.common.quadruped.config import QuadrupedConfig

    centre, half = robot.BASE_BOX
    return quadruped_mjcf(
        generated_comment(SOURCES, robot.LICENSE_NOTICE),
        robot.ROBOT_NAME,
        base="base",
        base_height=0.6,
        base_lines=[
            INDENT + _inertial(robot.BASE),
            f'{INDENT}<geom name="base" type="box" pos="{_v(centre)}" size="{_v(half)}" '
            'contype="1" conaffinity="1" condim="3" rgba="0.3 0.3 0.35 1"/>',
        ],
        base_box=robot.BASE_BOX,
        leg_lines=[line for leg in robot.LEGS for line in _leg(leg)],
        legs=robot.LEGS,
        joint_names=robot.JOINT_NAMES,
        actuator=actuator or Actuator.from_config(QuadrupedConfig()),
        torque_control=torque_control,
        timestep=timestep,
        gravity=robot.GRAVITY,
        foot_friction=foot_friction,
    )
