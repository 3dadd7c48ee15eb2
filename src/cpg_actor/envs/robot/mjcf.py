"""MJCF (MuJoCo) text of the hopper, generated from :mod:`description`.

The shipped file's physics timestep and foot friction are the defaults: the backend sets
``opt.timestep`` from ``HopperConfig.physics_dt`` (and the foot friction from
``HopperConfig.foot_friction``); :func:`simulated_mjcf` writes the configured ones in.
Contacts: elliptic friction cone with ``impratio`` 100, which makes MuJoCo's soft friction hard
enough that a standing foot sticks like PyBullet's rigid one instead of creeping (with the
defaults it creeps by ~1 cm/s under the standing load). The foot and the ground are the only
pair of geoms that can touch, so they are one explicit ``<pair>`` (:func:`contact_xml`) and no
geom collides on its own: MuJoCo then skips its broad phase, with the same contact, bit for
bit, and less work per substep.

Each leg joint carries a ``dcmotor`` actuator that is the law of
:mod:`cpg_actor.envs.actuator` (PD on the desired position, torque-speed line, torque limit),
so the simulator runs it at every substep with no Python in between; its control is the
desired joint position. An ``actuatorfrc`` sensor per joint reports the torque applied. The
shipped file has the default actuator constants; the backend writes the configured ones
(:func:`actuator_xml`).
"""

from __future__ import annotations

from cpg_actor.envs.robot import description as robot


def _v(values) -> str:
    return " ".join(f"{float(v):.6g}" for v in values)


def exact(value: float) -> str:
    """``value`` as the shortest decimal that reads back as the same double (a configured
    timestep or friction, written into the MJCF of :func:`simulated_mjcf`)."""
    return repr(float(value))


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


def preamble(
    model: str,
    timestep: float,
    texrepeat: int,
    foot_friction: float = robot.FOOT_FRICTION,
    actuation: bool = True,
) -> list[str]:
    """The MJCF from ``<mujoco>`` to ``</asset>`` shared by this project's robots: compiler,
    options (Euler, elliptic cone, impratio 100), defaults (the foot's contact class, geoms
    without collision or mass unless they say so) and the ground's checker texture.
    ``actuation=False`` switches the actuators off (``actuator_law="coast"``: the law is
    applied as joint torques)."""
    option = (
        f'  <option timestep="{exact(timestep)}" gravity="0 0 {-robot.GRAVITY:.6g}" '
        'integrator="Euler" cone="elliptic" impratio="100"'
    )
    return [
        f'<mujoco model="{model}">',
        '  <compiler angle="radian" autolimits="true"/>',
        option + ("/>" if actuation else '><flag actuation="disable"/></option>'),
        '  <visual><global offwidth="1280" offheight="960"/></visual>',
        "  <default>",
        '    <joint damping="0" armature="0" limited="true"/>',
        '    <geom contype="0" conaffinity="0" density="0"/>',
        '    <default class="visual"><geom rgba="0.85 0.35 0.1 1"/></default>',
        f'    <default class="foot"><geom contype="1" conaffinity="1" condim="3" '
        f'friction="{exact(foot_friction)} 0 0" solref="0.005 1" rgba="0.1 0.1 0.1 1"/>'
        "</default>",
        "  </default>",
        "  <asset>",
        '    <texture name="grid" type="2d" builtin="checker" width="256" height="256" '
        'rgb1="0.75 0.78 0.8" rgb2="0.6 0.63 0.66"/>',
        f'    <material name="grid" texture="grid" texrepeat="{texrepeat} {texrepeat}" '
        'reflectance="0.1"/>',
        "  </asset>",
    ]


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


def actuator_xml(
    actuator=None,
    indent: str = "  ",
    torque_control: bool = False,
    joint_names: tuple[str, ...] = robot.JOINT_NAMES,
) -> list[str]:
    """The ``<actuator>`` and ``<sensor>`` elements for :class:`cpg_actor.envs.actuator.Actuator`
    constants (default: those of the default ``HopperConfig``).

    MuJoCo's ``dcmotor`` with ``input="pos"`` commands the torque ``Kp (u - q) - Kd q_dot``
    through a driver voltage clamped to ``V``; ``nominal="V tau_sat v_max"`` makes the motor's
    torque-speed line ``tau_sat (+-1 - q_dot / v_max)`` at that clamp, and ``saturation`` clips
    the torque to ``tau_max``. ``V`` = 1 volt is arbitrary: only the ratios matter.

    ``torque_control``: plain ``motor`` actuators whose control is the joint torque, and no
    sensors, for MJX (which has no ``dcmotor``): the MJX backend computes the same law itself
    at every substep (:mod:`cpg_actor.envs.mjx.dynamics`).

    ``joint_names``: the actuated joints (default: the hopper's; the quadruped passes its 12).
    """
    inner = indent + "  "
    if torque_control:
        return [
            f"{indent}<actuator>",
            *(f'{inner}<motor name="{j}" joint="{j}"/>' for j in joint_names),
            f"{indent}</actuator>",
        ]
    if actuator is None:
        from cpg_actor.envs.actuator import Actuator
        from cpg_actor.envs.config import HopperConfig

        actuator = Actuator.from_config(HopperConfig())
    a = actuator
    motor = (
        f'input="pos" nominal="1 {a.saturation_torque:.17g} {a.velocity_limit:.17g}" '
        f'controller="{a.kp:.17g} 0 {a.kd:.17g} 0 0 1" saturation="{a.torque_limit:.17g} 0 0"'
    )
    return [
        f"{indent}<actuator>",
        *(f'{inner}<dcmotor name="{j}" joint="{j}" {motor}/>' for j in joint_names),
        f"{indent}</actuator>",
        f"{indent}<sensor>",
        *(f'{inner}<actuatorfrc name="{j}_torque" actuator="{j}"/>' for j in joint_names),
        f"{indent}</sensor>",
    ]


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
            "<!-- Generated by `python -m cpg_actor.envs.robot` from",
            "     cpg_actor/envs/robot/description.py: edit that file, not this one. -->",
            *preamble(
                robot.ROBOT_NAME,
                timestep,
                texrepeat=8,
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
            *actuator_xml(actuator, torque_control=torque_control),
            "</mujoco>",
            "",
        ]
    )


def simulated_mjcf(config) -> str:
    """The MJCF of the model the MuJoCo backend simulates under ``config`` (a
    :class:`~cpg_actor.envs.config.HopperConfig`): its actuators, timestep and foot friction
    written in, and with ``actuator_law="coast"`` the actuators switched off (the backend then
    applies the law as joint torques). Loaded, it is the backend's model field for field
    (``tests/test_export.py``); ``cpg-actor export`` writes it next to the policy."""
    from cpg_actor.envs.actuator import Actuator

    return mjcf_text(Actuator.from_config(config), timestep=config.physics_dt,
                     foot_friction=config.foot_friction)  # fmt: skip
