"""The MJCF document of a quadruped, as every quadruped's ``mjcf.py`` writes it: the head
(:func:`cpg_actor.robots.common.mjcf.preamble`), the checkered ground, the free base with its
IMU site and the touch site over its box, the robot's legs, the actuators of the actuator law
and the task's sensors (:data:`cpg_actor.robots.common.quadruped.model.SENSORS`). A robot's
writer gives what is its own: the base's inertia and shapes and the legs' bodies."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from cpg_actor.robots.common.mjcf import actuator_xml, exact, numbers, preamble

# the bodies' indentation inside the base
INDENT = "      "


def task_sensors(legs: Sequence[str]) -> list[str]:
    """The ``<sensor>`` element of :data:`~cpg_actor.robots.common.quadruped.model.SENSORS`:
    base angular and linear velocity (base frame), the feet's world positions, the normal force
    on the base's touch site."""
    return [
        "  <sensor>",
        '    <gyro name="base_ang_vel" site="imu"/>',
        '    <velocimeter name="base_lin_vel" site="imu"/>',
        *(f'    <framepos name="{leg}_foot_pos" objtype="site" objname="{leg}_foot"/>'
          for leg in legs),
        '    <touch name="base_touch" site="base_touch"/>',
        "  </sensor>",
    ]  # fmt: skip


def quadruped_mjcf(
    comment: Sequence[str],
    model: str,
    base: str,
    base_height: float,
    base_lines: Sequence[str],
    base_box: tuple[Sequence[float], Sequence[float]],
    leg_lines: Sequence[str],
    legs: Sequence[str],
    joint_names: Sequence[str],
    actuator: Any,
    torque_control: bool,
    timestep: float,
    gravity: float,
    foot_friction: float,
) -> str:
    """The complete MJCF document. ``comment``: its opening comment
    (:func:`cpg_actor.robots.common.notice.generated_comment`); ``model``: its name; ``base``:
    the free body's name, started ``base_height`` above the ground; ``base_lines``: the base's
    inertial and shapes, and ``leg_lines`` its legs' bodies (indented :data:`INDENT`);
    ``base_box`` (centre, half sizes): the box the touch site covers, 2 mm larger; ``legs``:
    the feet's names (sites ``<leg>_foot``); ``actuator``: the law's constants on the joints
    ``joint_names`` (``torque_control``: plain motors and no sensors, for MJX); the physics
    ``timestep``, ``gravity`` and the feet's and the ground's sliding ``foot_friction``."""
    centre, half = base_box
    return "\n".join(
        [
            *comment,
            *preamble(model, timestep, 40, gravity, foot_friction),
            "  <worldbody>",
            '    <light pos="0 -3 4" dir="0 0.6 -1" diffuse="0.8 0.8 0.8"/>',
            '    <geom name="ground" type="plane" size="50 50 0.05" material="grid" '
            f'contype="1" conaffinity="1" condim="3" friction="{exact(foot_friction)} 0 0"/>',
            f'    <body name="{base}" pos="0 0 {base_height:.6g}">',
            f'      <freejoint name="{base}"/>',
            *base_lines,
            f'{INDENT}<site name="imu" pos="0 0 0" size="0.01"/>',
            f'{INDENT}<site name="base_touch" type="box" pos="{numbers(centre)}" '
            f'size="{numbers(h + 0.002 for h in half)}" rgba="0 0 0 0"/>',
            *leg_lines,
            "    </body>",
            "  </worldbody>",
            *actuator_xml(actuator, tuple(joint_names), torque_control=torque_control),
            *([] if torque_control else task_sensors(legs)),
            "</mujoco>",
            "",
        ]
    )
