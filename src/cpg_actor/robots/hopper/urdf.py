"""URDF (PyBullet) text of the hopper, generated from :mod:`description`.

The root link ``world`` is massless and fixed (load with ``useFixedBase=True``); the rail is a
prismatic joint whose position is the hip height. Only the foot sphere has a collision shape.
Load with ``flags=URDF_USE_INERTIA_FROM_FILE``, or PyBullet recomputes inertias from shapes.
"""

from __future__ import annotations

from pathlib import Path

from cpg_actor.robots.common.mjcf import numbers
from cpg_actor.robots.common.notice import generated_comment
from cpg_actor.robots.hopper import description as robot
from cpg_actor.robots.hopper.mjcf import SOURCES

URDF_PATH = Path(__file__).resolve().parent / "assets" / f"{robot.ROBOT_NAME}.urdf"


def _v(values) -> str:
    return numbers(values, digits=6)


def _capsule_origin(start, end) -> tuple[tuple[float, float, float], float, float, float]:
    """Centre, length and (roll, pitch) of a capsule between two points (URDF cylinders are z)."""
    import math

    d = [e - s for s, e in zip(start, end, strict=True)]
    length = math.sqrt(sum(c * c for c in d))
    centre = tuple((s + e) / 2 for s, e in zip(start, end, strict=True))
    pitch = math.atan2(d[0], d[2]) if length else 0.0
    roll = -math.asin(d[1] / length) if length else 0.0
    return centre, length, roll, pitch


def _link(name: str) -> list[str]:
    link = robot.LINKS[name]
    ixx, iyy, izz = link.inertia
    lines = [
        f'  <link name="{name}">',
        "    <inertial>",
        f'      <origin xyz="{_v(link.com)}" rpy="0 0 0"/>',
        f'      <mass value="{link.mass:.6g}"/>',
        f'      <inertia ixx="{ixx:.6g}" ixy="0" ixz="0" iyy="{iyy:.6g}" iyz="0" izz="{izz:.6g}"/>',
        "    </inertial>",
    ]
    for link_name, kind, size, start, end in robot.VISUALS:
        if link_name != name:
            continue
        if kind == "box":
            geometry = f'<box size="{_v(2 * s for s in size)}"/>'
            origin = f'<origin xyz="{_v(start)}" rpy="0 0 0"/>'
        else:
            centre, length, roll, pitch = _capsule_origin(start, end)
            geometry = f'<capsule radius="{size:.6g}" length="{length:.6g}"/>'
            origin = f'<origin xyz="{_v(centre)}" rpy="{roll:.6g} {pitch:.6g} 0"/>'
        lines += [
            "    <visual>",
            f"      {origin}",
            f"      <geometry>{geometry}</geometry>",
            '      <material name="orange"><color rgba="0.85 0.35 0.1 1"/></material>',
            "    </visual>",
        ]
    if name == robot.FOOT_LINK:
        sphere = f'<sphere radius="{robot.FOOT_RADIUS:.6g}"/>'
        origin = f'<origin xyz="{_v(robot.FOOT_CENTER)}" rpy="0 0 0"/>'
        lines += [
            "    <visual>",
            f"      {origin}",
            f"      <geometry>{sphere}</geometry>",
            '      <material name="black"><color rgba="0.1 0.1 0.1 1"/></material>',
            "    </visual>",
            "    <collision>",
            f"      {origin}",
            f"      <geometry>{sphere}</geometry>",
            "    </collision>",
            "    <contact>",
            f'      <lateral_friction value="{robot.FOOT_FRICTION:.6g}"/>',
            "    </contact>",
        ]
    lines.append("  </link>")
    return lines


def urdf_text() -> str:
    """The complete URDF document."""
    lines = [
        '<?xml version="1.0"?>',
        *generated_comment(SOURCES, robot.LICENSE_NOTICE),
        f'<robot name="{robot.ROBOT_NAME}">',
        '  <link name="world"/>',
    ]
    for name in robot.LINKS:
        lines += _link(name)
    for joint in robot.JOINTS:
        lines += [
            f'  <joint name="{joint.name}" type="{joint.kind}">',
            f'    <parent link="{joint.parent}"/>',
            f'    <child link="{joint.child}"/>',
            f'    <origin xyz="{_v(joint.origin)}" rpy="0 0 0"/>',
        ]
        if joint.kind != "fixed":
            lo, hi = joint.limits
            lines += [
                f'    <axis xyz="{_v(joint.axis)}"/>',
                f'    <limit lower="{lo:.6g}" upper="{hi:.6g}" effort="1000" velocity="1000"/>',
                '    <dynamics damping="0" friction="0"/>',
            ]
        lines.append("  </joint>")
    lines += ["</robot>", ""]
    return "\n".join(lines)
