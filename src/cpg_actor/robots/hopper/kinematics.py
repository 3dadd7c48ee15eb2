"""Planar statics of the hopper, by hand: the leg's kinematics
(:mod:`cpg_actor.robots.anymal_leg.kinematics`) on the rail, with the hopper's link masses.
Used to place the robot on the ground at reset, by the reward, and by the tests as the
independent reference the simulators are checked on. The batched functions take numpy arrays
(float64) or JAX arrays (the MJX backend calls them inside ``jax.jit``;
:mod:`cpg_actor.robots.common.array_namespace`).
"""

from __future__ import annotations

import functools

import numpy as np

from cpg_actor.robots.anymal_leg.kinematics import (
    ADAPTER_IN_SHANK,
    HFE_ORIGIN,
    foot_position,
    knee_position,
    rotate,
)
from cpg_actor.robots.common.array_namespace import as_float, namespace
from cpg_actor.robots.hopper import description as robot


def standing_hip_height(joint_pos: np.ndarray) -> np.ndarray:
    """Hip height at which the foot sphere just touches the ground (z = 0) in this pose."""
    return robot.FOOT_RADIUS - foot_position(joint_pos)[..., 1]


def com_positions(joint_pos) -> dict[str, tuple[float, float]]:
    """COM (x, z) of every link in the hip frame."""
    q1, q2 = float(joint_pos[0]), float(joint_pos[1])
    knee = knee_position(np.array([q1, q2]))
    hip = robot.LINKS["hip"].com
    thigh = robot.LINKS["thigh"].com
    shank = robot.LINKS["shank"].com
    adapter = robot.LINKS["adapter"].com
    tx, tz = rotate(q1, thigh[0], thigh[2])
    sx, sz = rotate(q1 + q2, shank[0], shank[2])
    ax, az = rotate(q1 + q2, ADAPTER_IN_SHANK[0] + adapter[0], ADAPTER_IN_SHANK[1] + adapter[2])
    return {
        "hip": (hip[0], hip[2]),
        "thigh": (HFE_ORIGIN[0] + tx, HFE_ORIGIN[1] + tz),
        "shank": (float(knee[0] + sx), float(knee[1] + sz)),
        "adapter": (float(knee[0] + ax), float(knee[1] + az)),
    }


def com_height_offset(joint_pos: np.ndarray) -> np.ndarray:
    """Height of the whole robot's centre of mass above the hip (HFE axis frame origin), for
    joint positions ``(..., 2)``: the mass-weighted z of :func:`com_positions`, batched."""
    q = as_float(namespace(joint_pos), joint_pos)
    links = robot.LINKS
    knee_z = knee_position(q)[..., 1]
    thigh, shank, adapter = links["thigh"].com, links["shank"].com, links["adapter"].com
    thigh_z = HFE_ORIGIN[1] + rotate(q[..., 0], thigh[0], thigh[2])[1]
    leg = q[..., 0] + q[..., 1]
    shank_z = knee_z + rotate(leg, shank[0], shank[2])[1]
    adapter_z = (
        knee_z + rotate(leg, ADAPTER_IN_SHANK[0] + adapter[0], ADAPTER_IN_SHANK[1] + adapter[2])[1]
    )
    weighted = (
        links["hip"].mass * links["hip"].com[2]
        + links["thigh"].mass * thigh_z
        + links["shank"].mass * shank_z
        + links["adapter"].mass * adapter_z
    )
    return weighted / robot.TOTAL_MASS


def com_vertical_velocity(
    hip_velocity: np.ndarray, joint_pos: np.ndarray, joint_vel: np.ndarray
) -> np.ndarray:
    """Vertical velocity of the centre of mass: the hip's plus d/dt of
    :func:`com_height_offset` (central difference along the joint velocity)."""
    xp = namespace(hip_velocity, joint_pos, joint_vel)
    q, qd = as_float(xp, joint_pos), as_float(xp, joint_vel)
    if xp is np:
        h = 1e-6
        rate = (com_height_offset(q + h * qd) - com_height_offset(q - h * qd)) / (2 * h)
    else:  # float32: the exact directional derivative instead of a difference
        import jax

        rate = jax.jvp(com_height_offset, (q,), (qd,))[1]
    return as_float(xp, hip_velocity) + rate


@functools.cache  # pure, and asked for at every step of the apex reward
def highest_standing_com(resolution: int = 61) -> float:
    """The highest the centre of mass gets with the foot on the ground, over a grid of poses
    within the joint limits: a hop's apex above it is height no standing pose reaches."""
    hfe, kfe = (robot.JOINT_LIMITS[name] for name in robot.JOINT_NAMES)
    grid = np.stack(
        np.meshgrid(np.linspace(*hfe, resolution), np.linspace(*kfe, resolution)), axis=-1
    ).reshape(-1, 2)
    return float(np.max(standing_hip_height(grid) + com_height_offset(grid)))


def standing_torques(joint_pos, gravity: float = robot.GRAVITY) -> np.ndarray:
    """Joint torques (HFE, KFE) that hold the leg still, standing on a frictionless floor.

    The rail carries no vertical load, so the ground pushes the foot up with the whole weight
    ``M g``; without friction that force is vertical. Moment balance of the part of the leg
    below each joint, about that joint's axis (x is the horizontal lever arm, positive forward;
    a positive torque about +y turns forward-pointing arms downwards, so the ground force in
    front of a joint needs a positive holding torque and the weight in front a negative one)::

        tau_KFE = M g (x_foot - x_KFE) - g * sum_{shank, adapter} m_i (x_i - x_KFE)
        tau_HFE = M g (x_foot - x_HFE) - g * sum_{thigh, shank, adapter} m_i (x_i - x_HFE)
    """
    coms = com_positions(joint_pos)
    foot_x = float(foot_position(np.asarray(joint_pos, dtype=np.float64))[0])
    knee_x = float(knee_position(np.asarray(joint_pos, dtype=np.float64))[0])
    hfe_x = HFE_ORIGIN[0]
    weight = robot.TOTAL_MASS * gravity

    def moment(names, axis_x):
        return gravity * sum(robot.LINKS[n].mass * (coms[n][0] - axis_x) for n in names)

    tau_kfe = weight * (foot_x - knee_x) - moment(("shank", "adapter"), knee_x)
    tau_hfe = weight * (foot_x - hfe_x) - moment(("thigh", "shank", "adapter"), hfe_x)
    return np.array([tau_hfe, tau_kfe])
