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

A control step of the task (:func:`step`) is written once: the physics of each simulator hands
it a :class:`Reading`, the task carries an :class:`Episode` from step to step, and it returns
the observation, reward, terminations, episode metrics and the step's info. Masks are
``where``, never Python branches on values, so that JAX can trace them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

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


def sensor_noise(num_joints: int) -> np.ndarray:
    """The sensors' noise, std per observation entry (a perturbation's ``obs_noise`` = 1):
    legged_gym's noise scales (Rudin et al. 2021), there uniform, here Gaussian: gyro 0.2
    rad/s, projected gravity 0.05, joint encoders 0.01 rad, joint speeds 1.5 rad/s; the
    command and the last action carry none."""
    j = num_joints
    return np.concatenate([np.full(3, 0.2), np.full(3, 0.05), np.zeros(3), np.full(j, 0.01),
                           np.full(j, 1.5), np.zeros(j)])  # fmt: skip


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


def lin_vel_error(lin_vel, command):
    """(N,) m/s: how far the base's horizontal velocity is from the commanded one,
    ``|v_xy - command_xy|``, both in the base frame (the frame the command is given in, as
    the tracking reward's); 0 for a robot walking exactly at its command."""
    xp = namespace(lin_vel)
    return xp.sqrt(xp.sum((lin_vel[:, :2] - command[:, :2]) ** 2, axis=1))


def yaw_rate_error(ang_vel, command):
    """(N,) rad/s: ``|w_z - command_yaw|``, the base's yaw rate (the gyro's z, base frame)
    against the commanded one; the same for a turn too fast or too slow, left or right."""
    xp = namespace(ang_vel)
    return xp.abs(ang_vel[:, 2] - command[:, 2])


def fallen(base_height, gravity, fall_height: float, fall_tilt: float) -> np.ndarray:
    """(N,) bool: the base is below ``fall_height`` or tilted more than ``fall_tilt`` rad."""
    xp = namespace(gravity)
    tilt = xp.arccos(xp.clip(-gravity[:, 2], -1.0, 1.0))
    return (base_height < fall_height) | (tilt > fall_tilt)


# ---------------------------------------------------------------------------------------------
# one control step, for any simulator

EPISODE_METRICS = ("speed_error", "forward_speed", "fell", "episode_seconds", "cost_of_transport",
                   "foot_slip", "lin_vel_error", "yaw_rate_error", "duty_factor",
                   "planar_cost_of_transport", "lin_vel_offset", "yaw_rate_offset")  # fmt: skip
MIN_DISTANCE = 0.1  # m: below this the cost of transport is not defined (NaN)
CONTACT_MARGIN = 0.005  # m: a foot whose centre is within its radius plus this touches the ground
MOVING = 0.1  # m/s: a command faster than this pays the feet's air time


class Episode(NamedTuple):
    """What the task carries from one control step to the next, N rows each."""

    command: Any  # (N, 3) forward, lateral (m/s), yaw (rad/s) command
    last_action: Any  # (N, J) desired positions of the last step, rad
    joint_vel_before: Any  # (N, J) joint velocities after the last step
    elapsed: Any  # (N,) int, control steps of the episode
    air_time: Any  # (N, 4) s since each foot left the ground
    in_contact: Any  # (N, 4) bool
    speed_error_sum: Any  # (N,) sum of |forward speed - command|
    speed_sum: Any  # (N,) sum of the forward speed
    work: Any  # (N,) J, the joints' mechanical work (|torque x speed| dt)
    start_x: Any  # (N,) the base's x at the episode's start, m
    slip_sum: Any  # (N,) sum of the planted feet's sliding speeds, m/s
    planted_steps: Any  # (N,) int, count of planted feet over the episode's steps
    feet_xy: Any  # (N, 4, 2) the feet's horizontal positions at the last reading, m
    # the omnidirectional task's tracking (the evaluation protocol's, docs/quadruped.md)
    lin_vel_error_sum: Any  # (N,) sum of |v_xy - command_xy| in the base frame, m/s
    yaw_rate_error_sum: Any  # (N,) sum of |yaw rate - command yaw|, rad/s
    contact_steps: Any  # (N,) int, count of feet on the ground over the episode's steps
    path_length: Any  # (N,) m the base travelled in the plane: the sum of |v_xy| dt
    # (N, 3) sum of (v_x, v_y, w_z) - command: its mean is the tracking's offset, the gait's
    # sway within a stride averaged out
    velocity_offset_sum: Any


class Reading(NamedTuple):
    """What a simulator's physics hands the task after a control step, N rows each."""

    qpos: Any  # (N, 7 + J) free base (position, quaternion w x y z), then the joints
    qvel: Any  # (N, 6 + J)
    lin_vel: Any  # (N, 3) the base's linear velocity in the base frame, m/s
    ang_vel: Any  # (N, 3) the base's angular velocity in the base frame (the gyro), rad/s
    feet: Any  # (N, 4, 3) the feet's positions (world), m
    torque: Any  # (N, J) the joint torques of the last physics substep, N m
    work: Any  # (N,) the joints' mechanical work over the step, J
    base_touch: Any  # (N,) bool: the base touches the ground
    unstable: Any  # (N,) bool: the simulation blew up (non-finite state)


def desired_positions(actions, low, high, normalized: bool):
    """Actions to desired joint positions within ``low`` .. ``high`` (J,): the actions are the
    positions (rad), or with ``normalized`` in [-1, 1] from the lower to the upper limit."""
    xp = namespace(actions)
    if normalized:
        actions = low + (xp.clip(actions, -1.0, 1.0) + 1.0) * (high - low) / 2
    return xp.clip(actions, low, high)


def new_episode(command, joints, start_x, feet_xy) -> Episode:
    """A fresh :class:`Episode` for robots at rest in ``joints`` (N, J) under ``command``."""
    xp = namespace(joints)
    n = joints.shape[0]
    zero = xp.zeros_like(start_x)
    count = xp.zeros(n, dtype=int)
    return Episode(
        command=command, last_action=joints, joint_vel_before=xp.zeros_like(joints),
        elapsed=count, air_time=xp.zeros((n, 4), dtype=joints.dtype),
        in_contact=xp.ones((n, 4), dtype=bool), speed_error_sum=zero, speed_sum=zero, work=zero,
        start_x=start_x, slip_sum=zero, planted_steps=count, feet_xy=feet_xy,
        lin_vel_error_sum=zero, yaw_rate_error_sum=zero, contact_steps=count,
        path_length=zero, velocity_offset_sum=xp.zeros_like(command),
    )  # fmt: skip


def restart(episode: Episode, done, fresh: Episode) -> Episode:
    """``episode`` with the rows of ``done`` (N,) taken from ``fresh``."""
    return Episode(*(rows(done, new, old) for new, old in zip(fresh, episode, strict=True)))


def rows(mask, new, old):
    """``new`` where ``mask`` (N,) is set, else ``old``: rows of arrays of any rank."""
    xp = namespace(old)
    return xp.where(mask.reshape((-1,) + (1,) * (old.ndim - 1)), new, old)


COMMAND = slice(6, 9)  # the command's entries in the observation


def resample(episode: Episode, obs, command, due) -> tuple[Episode, Any]:
    """``episode`` and its observation ``obs`` (N, 9 + 3 J) with the rows of ``due`` (N,) under
    ``command`` (N, 3): the command drawn again within an episode, which the next step runs
    under and the observation now shows."""
    xp = namespace(obs)
    command = rows(due, command, episode.command)
    shown = xp.concatenate([obs[:, : COMMAND.start], command.astype(obs.dtype),
                            obs[:, COMMAND.stop :]], axis=1)  # fmt: skip
    return episode._replace(command=command), rows(due, shown, obs)


def observe(qpos, qvel, ang_vel, command, last_action, nominal):
    """:func:`observation` of the state after a step (non-finite entries 0)."""
    xp = namespace(qpos)
    obs = observation(ang_vel, projected_gravity(qpos[:, 3:7]), command, qpos[:, 7:],
                      qvel[:, 6:], last_action, nominal)  # fmt: skip
    return xp.nan_to_num(obs, nan=0.0, posinf=0.0, neginf=0.0)


def step(config, episode: Episode, reading: Reading, desired, nominal, foot_radius: float,
         weight: float) -> tuple[Episode, dict]:  # fmt: skip
    """One control step of the task: ``(episode, outputs)``, the episode after the step (not
    yet restarted where it ended) and ``obs`` (the step's last observation), ``reward``,
    ``reward_terms`` (scaled), ``terminated``, ``truncated``, ``episode_metrics`` (NaN for
    the robots whose episode goes on) and ``info`` (``command``, ``contact``,
    ``base_height``, ``forward_speed``, ``desired_position``, ``measured_position``,
    ``measured_velocity``, ``joint_torque`` (N, J, N m) and ``foot_position`` (N, 4, 3, the
    feet in the world, m): the physical metrics' inputs).

    ``config``: the env's (scales, sigma, fall limits, steps); ``desired`` (N, J) the positions
    the step tracked; ``nominal`` (J,) the nominal pose; ``weight`` m g (N), the cost of
    transport's."""
    xp = namespace(reading.qpos)
    dt, unstable = config.control_dt, reading.unstable
    qpos, qvel, lin_vel, ang_vel, feet = (reading.qpos, reading.qvel, reading.lin_vel,
                                          reading.ang_vel, reading.feet)  # fmt: skip
    gravity = projected_gravity(qpos[:, 3:7])
    height = qpos[:, 2]
    joint_vel = qvel[:, 6:]
    joint_acc = (joint_vel - episode.joint_vel_before) / dt
    contact = feet[:, :, 2] < foot_radius + CONTACT_MARGIN
    slip, planted = planted_slip(feet[:, :, :2], episode.feet_xy, contact, episode.in_contact,
                                 dt)  # fmt: skip
    touchdown = contact & ~episode.in_contact
    air_time = episode.air_time + dt
    moving = xp.linalg.norm(episode.command[:, :2], axis=1) > MOVING
    air_paid = xp.sum((air_time - 0.5) * touchdown, axis=1) * moving
    terms = reward_terms(
        lin_vel, ang_vel, gravity, height, episode.command, reading.torque, joint_acc, desired,
        episode.last_action, air_paid, slip, config.tracking_sigma, config.base_height_target,
    )  # fmt: skip
    scaled = {name: xp.where(unstable, 0.0, value * config.reward_scales[name] * dt)
              for name, value in terms.items()}  # fmt: skip
    terminated = (fallen(height, gravity, config.fall_height, config.fall_tilt)
                  | reading.base_touch | unstable)  # fmt: skip
    after = Episode(
        command=episode.command, last_action=desired, joint_vel_before=joint_vel,
        elapsed=episode.elapsed + 1, air_time=xp.where(contact, 0.0, air_time),
        in_contact=contact,
        speed_error_sum=episode.speed_error_sum + xp.abs(lin_vel[:, 0] - episode.command[:, 0]),
        speed_sum=episode.speed_sum + lin_vel[:, 0], work=episode.work + reading.work,
        start_x=episode.start_x, slip_sum=episode.slip_sum + slip.sum(axis=1),
        planted_steps=episode.planted_steps + planted.sum(axis=1), feet_xy=feet[:, :, :2],
        lin_vel_error_sum=episode.lin_vel_error_sum + lin_vel_error(lin_vel, episode.command),
        yaw_rate_error_sum=episode.yaw_rate_error_sum + yaw_rate_error(ang_vel, episode.command),
        contact_steps=episode.contact_steps + contact.sum(axis=1),
        path_length=episode.path_length + xp.sqrt(xp.sum(lin_vel[:, :2] ** 2, axis=1)) * dt,
        velocity_offset_sum=episode.velocity_offset_sum + xp.concatenate(
            [lin_vel[:, :2], ang_vel[:, 2:]], axis=1) - episode.command,
    )  # fmt: skip
    truncated = (after.elapsed >= config.episode_steps) & ~terminated
    done = terminated | truncated
    obs = observe(qpos, qvel, ang_vel, episode.command, desired, nominal)
    outputs = {
        "obs": xp.where(unstable[:, None], xp.zeros_like(obs), obs),
        "reward": sum(scaled.values()),
        "reward_terms": scaled,
        "terminated": terminated,
        "truncated": truncated,
        "episode_metrics": episode_metrics(after, qpos[:, 0], terminated, done, dt, weight),
        "info": {
            "command": episode.command, "contact": contact, "base_height": height,
            "forward_speed": lin_vel[:, 0], "desired_position": desired,
            "measured_position": qpos[:, 7:], "measured_velocity": joint_vel,
            "joint_torque": reading.torque, "foot_position": feet,
        },
    }  # fmt: skip
    return after, outputs


def episode_metrics(episode: Episode, x, fell, done, dt: float, weight: float) -> dict:
    """The :data:`EPISODE_METRICS` of the episodes that ended (``done``), NaN elsewhere; ``x``
    (N,) the base's position now, ``fell`` (N,) bool.

    ``cost_of_transport`` divides by the distance walked forward (world x: the forward
    task's); ``planar_cost_of_transport`` by the length of the base's path in the plane,
    whichever way it walked, curves too (the omnidirectional task's). ``lin_vel_error`` and
    ``yaw_rate_error`` are the means of the per-step errors (what the tracking reward sees,
    the gait's sway within a stride included); ``lin_vel_offset`` and ``yaw_rate_offset`` the
    errors of the mean, ``|mean(v_xy - command_xy)|`` and ``|mean(w_z - command_yaw)|``: how
    far the robot's average motion is from the command, the sway averaged out."""
    xp = namespace(x)
    steps = episode.elapsed.astype(episode.speed_sum.dtype)
    distance = x - episode.start_x
    planar = episode.path_length
    planted = episode.planted_steps
    contact_count = episode.in_contact.shape[1]  # the feet
    forward_cost = episode.work / (weight * xp.maximum(distance, MIN_DISTANCE))
    planar_cost = episode.work / (weight * xp.maximum(planar, MIN_DISTANCE))
    offset = episode.velocity_offset_sum / steps[:, None]
    metrics = {
        "speed_error": episode.speed_error_sum / steps,
        "forward_speed": episode.speed_sum / steps,
        "fell": fell.astype(steps.dtype),
        "episode_seconds": steps * dt,
        "cost_of_transport": xp.where(distance >= MIN_DISTANCE, forward_cost, xp.nan),
        "foot_slip": xp.where(planted > 0, episode.slip_sum / xp.maximum(planted, 1), xp.nan),
        "lin_vel_error": episode.lin_vel_error_sum / steps,
        "yaw_rate_error": episode.yaw_rate_error_sum / steps,
        "duty_factor": episode.contact_steps.astype(steps.dtype) / (contact_count * steps),
        "planar_cost_of_transport": xp.where(planar >= MIN_DISTANCE, planar_cost, xp.nan),
        "lin_vel_offset": xp.sqrt(xp.sum(offset[:, :2] ** 2, axis=1)),
        "yaw_rate_offset": xp.abs(offset[:, 2]),
    }  # fmt: skip
    return {name: xp.where(done, value, xp.nan) for name, value in metrics.items()}
