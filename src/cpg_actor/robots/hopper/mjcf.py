"""MJCF (MuJoCo) text of the hopper, generated from :mod:`description`.

The shipped file's physics timestep and foot friction are the defaults: the backend sets
``opt.timestep`` from ``HopperConfig.physics_dt`` (and the foot friction from
``HopperConfig.foot_friction``); :func:`cpg_actor.robots.common.mjcf.simulated_mjcf` writes
the configured ones in (with ``actuator_law="coast"`` the actuators switched off: the backend
then applies the law as joint torques).
Contacts: elliptic friction cone with ``impratio`` 100, which makes MuJoCo's soft friction hard
enough that a standing foot sticks like PyBullet's rigid one instead of creeping (with the
defaults it creeps by ~1 cm/s under the standing load). The foot and the ground are the only
pair of geoms that can touch, so they are one explicit ``<pair>`` (:func:`contact_xml`) and no
geom collides on its own: MuJoCo then skips its broad phase, with the same contact, bit for
bit, and less work per substep.

Each leg joint carries a ``dcmotor`` actuator that is the law of
:mod:`cpg_actor.robots.common.actuator` (PD on the desired position, torque-speed line, torque
limit), so the simulator runs it at every substep with no Python in between; its control is the
desired joint position. An ``actuatorfrc`` sensor per joint reports the torque applied. The
shipped file has the default actuator constants; the backend writes the configured ones
(:func:`actuator_xml`).
"""

from __future__ import annotations

from pathlib import Path

from cpg_actor.robots.common.mjcf import actuator_xml, exact, numbers, preamble
from cpg_actor.robots.common.notice import generated_comment
from cpg_actor.robots.hopper import description as robot

# the descriptions both robot files are generated from
SOURCES = ("cpg_actor/robots/hopper/description.py", "cpg_actor/robots/anymal_leg/description.py")


def _v(values) -> str:
    return numbers(values, digits=6)


def _body(name: str, indent: str) -> list[str]:
    """Inertial, joint and geoms of ``name`` and, recursively, its children."""
    link = robot.LINKS[name]
    lines = [
        f'{indent}<inertial pos="{_v(link.com)}" mass="{link.mass:.6g}" '
        f'diaginertia="{_v(link.inertia)}"/>'
    ]
    for link_name, kind, size, start, end in robot.VISUALS:
        if link_name != name:
            continue
        if kind == "box":
            lines.append(
                f'{indent}<geom class="visual" type="box" size="{_v(size)}" pos="{_v(start)}"/>'
            )
        else:
            lines.append(
                f'{indent}<geom class="visual" type="capsule" size="{size:.6g}" '
                f'fromto="{_v(start)} {_v(end)}"/>'
            )
    if name == robot.FOOT_LINK:
        lines.append(
            f'{indent}<geom name="foot" class="foot" type="sphere" size="{robot.FOOT_RADIUS:.6g}" '
            f'pos="{_v(robot.FOOT_CENTER)}" contype="0" conaffinity="0"/>'
        )
        lines.append(f'{indent}<site name="foot" pos="{_v(robot.FOOT_CENTER)}" size="0.005"/>')
    for joint in robot.JOINTS:
        if joint.parent != name:
            continue
        lines.append(f'{indent}<body name="{joint.child}" pos="{_v(joint.origin)}">')
        inner = indent + "  "
        if joint.kind == "revolute":
            lo, hi = joint.limits
            lines.append(
                f'{inner}<joint name="{joint.name}" type="hinge" axis="{_v(joint.axis)}" '
                f'range="{lo:.6g} {hi:.6g}"/>'
            )
        lines.extend(_body(joint.child, inner))
        lines.append(f"{indent}</body>")
    return lines


# The foot-ground contact's solver reference (time constant s, damping ratio): the mix MuJoCo
# makes of the foot class's 0.005 and the ground's default 0.02 (equal solmix: the mean) for a
# contact found by collision detection (the quadruped's feet), so the pair is that contact
FOOT_SOLREF = (0.0125, 1.0)


def contact_xml(foot_friction: float = robot.FOOT_FRICTION) -> list[str]:
    """The ``<contact>`` element: the foot-ground ``<pair>``, condim 3 (sliding friction
    ``foot_friction`` in both tangent directions), solref ``FOOT_SOLREF``."""
    mu = exact(foot_friction)
    return [
        "  <contact>",
        f'    <pair name="foot_ground" geom1="foot" geom2="ground" condim="3" '
        f'friction="{mu} {mu}" solref="{_v(FOOT_SOLREF)}"/>',
        "  </contact>",
    ]


def set_foot_friction(model, friction: float) -> None:
    """Set the sliding friction of every foot-ground pair of ``model`` (an ``MjModel``)."""
    model.pair_friction[:, :2] = friction


MJCF_PATH = Path(__file__).resolve().parent / "assets" / f"{robot.ROBOT_NAME}.xml"


def default_actuator():
    """The actuator law's constants of the default :class:`HopperConfig`."""
    from cpg_actor.robots.common.actuator import Actuator
    from cpg_actor.robots.hopper.config import HopperConfig

    return Actuator.from_config(HopperConfig())


def mjcf_text(
    actuator=None,
    torque_control: bool = False,
    timestep: float = 0.001,
    foot_friction: float = robot.FOOT_FRICTION,
) -> str:
    """The complete MJCF document, with the actuators of :func:`actuator_xml`, the physics
    ``timestep`` and the foot-ground ``foot_friction`` (the shipped file: the defaults)."""
    rail = robot.JOINTS[0]
    lo, hi = rail.limits
    body = _body("hip", "      ")
    return "\n".join(
        [
            *generated_comment(SOURCES, robot.LICENSE_NOTICE),
            *preamble(
                robot.ROBOT_NAME,
                timestep,
                texrepeat=8,
                gravity=robot.GRAVITY,
                foot_friction=robot.FOOT_FRICTION,
                actuation=actuator is None or torque_control or actuator.law != "coast",
            ),
            "  <worldbody>",
            '    <light pos="0.5 -1.5 3" dir="-0.2 0.5 -1" diffuse="0.8 0.8 0.8"/>',
            '    <geom name="ground" type="plane" size="2 2 0.05" material="grid"/>',
            '    <geom name="rail_post" type="cylinder" size="0.01 0.6" pos="-0.03 0 0.6" '
            'rgba="0.5 0.5 0.55 1"/>',
            '    <body name="hip" pos="0 0 0">',
            f'      <joint name="{rail.name}" type="slide" axis="{_v(rail.axis)}" '
            f'range="{lo:.6g} {hi:.6g}"/>',
            *body,
            "    </body>",
            "  </worldbody>",
            *contact_xml(foot_friction),
            *actuator_xml(
                actuator or default_actuator(), robot.JOINT_NAMES, torque_control=torque_control
            ),
            "</mujoco>",
            "",
        ]
    )
