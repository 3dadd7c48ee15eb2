"""MJCF pieces every robot's description writes alike: numbers, the document's head (options,
defaults, the ground's texture), the actuators of the project's actuator law, and the model an
env config simulates."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


def exact(value: float) -> str:
    """``value`` as the shortest decimal that reads back as the same double (a configured
    timestep or friction, written into the MJCF of :func:`simulated_mjcf`)."""
    return repr(float(value))


def numbers(values, digits: int = 12) -> str:
    """``values`` as an MJCF (or URDF) list of numbers, ``digits`` significant digits each."""
    return " ".join(f"{float(v):.{digits}g}" for v in values)


def simulated_mjcf(mjcf_text: Callable[..., str], config: Any) -> str:
    """The MJCF of the model a robot's MuJoCo env simulates under its env ``config``: the
    robot's ``mjcf_text`` with the config's actuators, timestep and foot-ground friction written
    in. Loaded, it is the env's model field for field (``tests/deploy/test_export.py``);
    ``cpg-actor export`` writes it next to the policy (``Robot.mjcf``)."""
    from cpg_actor.robots.common.actuator import Actuator

    return mjcf_text(Actuator.from_config(config), timestep=config.physics_dt,
                     foot_friction=config.foot_friction)  # fmt: skip


def preamble(
    model: str,
    timestep: float,
    texrepeat: int,
    gravity: float,
    foot_friction: float,
    actuation: bool = True,
) -> list[str]:
    """The MJCF from ``<mujoco>`` to ``</asset>`` shared by this project's robots: compiler,
    options (Euler, elliptic cone, impratio 100), defaults (the foot's contact class, geoms
    without collision or mass unless they say so) and the ground's checker texture.
    ``actuation=False`` switches the actuators off (``actuator_law="coast"``: the law is
    applied as joint torques)."""
    option = (
        f'  <option timestep="{exact(timestep)}" gravity="0 0 {-gravity:.6g}" '
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


def actuator_xml(
    actuator,
    joint_names: tuple[str, ...],
    indent: str = "  ",
    torque_control: bool = False,
) -> list[str]:
    """The ``<actuator>`` and ``<sensor>`` elements for
    :class:`cpg_actor.robots.common.actuator.Actuator` constants on the joints ``joint_names``.

    MuJoCo's ``dcmotor`` with ``input="pos"`` commands the torque ``Kp (u - q) - Kd q_dot``
    through a driver voltage clamped to ``V``; ``nominal="V tau_sat v_max"`` makes the motor's
    torque-speed line ``tau_sat (+-1 - q_dot / v_max)`` at that clamp, and ``saturation`` clips
    the torque to ``tau_max``. ``V`` = 1 volt is arbitrary: only the ratios matter. Constants
    given per joint (or per joint of a leg) are written joint by joint.

    ``torque_control``: plain ``motor`` actuators whose control is the joint torque, and no
    sensors, for MJX (which has no ``dcmotor``): the MJX backend computes the same law itself
    at every substep (the hopper's :mod:`cpg_actor.robots.hopper.mjx.dynamics`).
    """
    inner = indent + "  "
    if torque_control:
        return [
            f"{indent}<actuator>",
            *(f'{inner}<motor name="{j}" joint="{j}"/>' for j in joint_names),
            f"{indent}</actuator>",
        ]
    n = len(joint_names)
    kp, kd, limit, speed, stall = (actuator.per_joint(name, n) for name in
                                   ("kp", "kd", "torque_limit", "velocity_limit",
                                    "saturation_torque"))  # fmt: skip

    def motor(i: int) -> str:
        return (
            f'input="pos" nominal="1 {stall[i]:.17g} {speed[i]:.17g}" '
            f'controller="{kp[i]:.17g} 0 {kd[i]:.17g} 0 0 1" saturation="{limit[i]:.17g} 0 0"'
        )

    return [
        f"{indent}<actuator>",
        *(
            f'{inner}<dcmotor name="{j}" joint="{j}" {motor(i)}/>'
            for i, j in enumerate(joint_names)
        ),  # fmt: skip
        f"{indent}</actuator>",
        f"{indent}<sensor>",
        *(f'{inner}<actuatorfrc name="{j}_torque" actuator="{j}"/>' for j in joint_names),
        f"{indent}</sensor>",
    ]
