"""Velocity tracking for a legged robot with a floating base, as pure functions of batched
arrays (N robots): numpy in the MuJoCo env, ``jax.numpy`` inside the MJX env's jitted step (the
module of the inputs is used). It knows no robot: the joints and the nominal pose come in as
arguments.

Observation (:func:`observation_names`, legged_gym's without the base linear velocity, which a
real robot does not measure): base angular velocity in the base frame (rad/s), gravity
projected into the base frame (unit vector), the command (forward, lateral m/s, yaw rad/s),
joint positions minus the nominal pose (rad), joint velocities (rad/s), the last action minus
the nominal pose (rad).

Reward: each term of :func:`reward_terms` times its scale (the env config's ``reward_scales``)
times the control step, summed (legged_gym's convention: the scales are per second).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cpg_actor.robots.common.array_namespace import namespace


def observation_names(joint_names: Sequence[str]) -> tuple[str, ...]:
    """The observation's entries, in order, for a robot with ``joint_names``."""
    return (
        *(f"base_ang_vel_{a}" for a in "xyz"),
        *(f"projected_gravity_{a}" for a in "xyz"),
        "command_vx", "command_vy", "command_yaw",
        *(f"{j}_pos" for j in joint_names),
        *(f"{j}_vel" for j in joint_names),
        *(f"{j}_last_action" for j in joint_names),
    )  # fmt: skip


def observation_sources(nominal_pose: Sequence[float]) -> tuple[dict, ...]:
    """Where each observation entry comes from in the MuJoCo model's data
    (:data:`cpg_actor.deploy.export.OBSERVATION_SOURCES`): qpos 0-6 and qvel 0-5 are the free
    base's, the joints follow in joint order."""
    nominal = [float(p) for p in nominal_pose]
    return (
        *({"source": "sensor", "sensor": "base_ang_vel", "index": i} for i in range(3)),
        *({"source": "projected_gravity", "quaternion": 3, "index": i} for i in range(3)),
        *({"source": "command", "index": i} for i in range(3)),
        *({"source": "qpos", "index": 7 + j, "offset": 0.0 - p} for j, p in enumerate(nominal)),
        *({"source": "qvel", "index": 6 + j} for j in range(len(nominal))),
        *({"source": "desired", "index": j, "offset": 0.0 - p} for j, p in enumerate(nominal)),
    )  # fmt: skip


def projected_gravity(quat: np.ndarray) -> np.ndarray:
    """(N, 3): the world's unit gravity (0, 0, -1) in the base frame, from the base quaternion
    (w, x, y, z): minus the third row of the rotation matrix. (0, 0, -1) when level."""
    xp = namespace(quat)
    w, x, y, z = (quat[:, i] for i in range(4))
    return -xp.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=1)


def observation(
    ang_vel, gravity, command, joint_pos, joint_vel, last_action, nominal
) -> np.ndarray:
    """(N, 9 + 3 J) float32 in the order of :func:`observation_names`; ``nominal`` the (J,)
    nominal pose."""
    xp = namespace(ang_vel, joint_pos)
    return xp.concatenate(
        [ang_vel, gravity, command, joint_pos - nominal, joint_vel, last_action - nominal], axis=1
    ).astype(xp.float32)


def planted_slip(feet_xy, feet_xy_before, contact, in_contact, dt: float):
    """How fast each planted foot slides: ``(slip, planted)``, both (N, 4).

    A foot is planted when it touches the ground at both ends of the control step (``contact``
    now, ``in_contact`` before); its slip is then its horizontal speed over the step,
    ``|xy - xy_before| / dt`` (m/s), and 0 elsewhere. A foot that rolls or stands has
    (nearly) none; one dragged along the ground has the body's speed."""
    xp = namespace(feet_xy)
    planted = contact & in_contact
    speed = xp.sqrt(xp.sum((feet_xy - feet_xy_before) ** 2, axis=-1)) / dt
    return xp.where(planted, speed, 0.0), planted


def reward_terms(
    lin_vel, ang_vel, gravity, base_height, command, torque, joint_acc, action, last_action,
    air_time_paid, slip, sigma: float, base_height_target: float,
) -> dict[str, np.ndarray]:  # fmt: skip
    """Each reward term, (N,) per robot, unscaled (``QuadrupedConfig`` holds the scales).

    ``lin_vel`` and ``ang_vel`` in the base frame (m/s, rad/s); ``air_time_paid``: per robot,
    the sum over the feet that touched down this step of (their air time - 0.5 s), 0 when the
    command is (nearly) zero, as legged_gym pays it; ``slip``: (N, 4) the planted feet's
    sliding speed (:func:`planted_slip`).
    """
    xp = namespace(lin_vel)
    return {
        "tracking_lin_vel": xp.exp(-xp.sum((command[:, :2] - lin_vel[:, :2]) ** 2, 1) / sigma),
        "tracking_ang_vel": xp.exp(-((command[:, 2] - ang_vel[:, 2]) ** 2) / sigma),
        "lin_vel_z": lin_vel[:, 2] ** 2,
        "ang_vel_xy": xp.sum(ang_vel[:, :2] ** 2, 1),
        "orientation": xp.sum(gravity[:, :2] ** 2, 1),
        "base_height": (base_height - base_height_target) ** 2,
        "torques": xp.sum(torque**2, 1),
        "joint_acc": xp.sum(joint_acc**2, 1),
        "action_rate": xp.sum((action - last_action) ** 2, 1),
        "feet_air_time": air_time_paid,
        "feet_slip": xp.sum(slip**2, 1),
    }


def fallen(base_height, gravity, fall_height: float, fall_tilt: float) -> np.ndarray:
    """(N,) bool: the base is below ``fall_height`` or tilted more than ``fall_tilt`` rad."""
    xp = namespace(gravity)
    tilt = xp.arccos(xp.clip(-gravity[:, 2], -1.0, 1.0))
    return (base_height < fall_height) | (tilt > fall_tilt)
