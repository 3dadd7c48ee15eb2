"""Velocity tracking for a legged robot with a floating base, as pure functions of batched
arrays (N robots): numpy in the MuJoCo env, ``jax.numpy`` inside the MJX env's jitted step (the
module of the inputs is used). It knows no robot: the joints and the nominal pose come in as
arguments.

Observation (:func:`observation_names`, legged_gym's without the base linear velocity, which a
real robot does not measure): base angular velocity in the base frame (rad/s), gravity
projected into the base frame (unit vector), the command (forward, lateral m/s, yaw rad/s),
joint positions minus the nominal pose (rad), joint velocities (rad/s), the last action minus
the nominal pose (rad); with ``observe_lin_vel`` (MuJoCo Playground's recipe) the base's linear
velocity in the base frame (m/s) after them, and with ``privileged_observation`` the critic's
privileged entries after those (:func:`privileged_names`; the actor does not see them).

Reward: each term of :func:`reward_terms` and :func:`field_terms` times its scale (the env
config's ``reward_scales``; a term it does not name is not paid) times the control step, summed
(legged_gym's convention: the scales are per second), then clipped below at
``reward_clip_min`` where that is set (MuJoCo Playground's and legged_gym's
``only_positive_rewards``: 0, so that ending an episode early never pays).

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


def observation_names(
    joint_names: Sequence[str], lin_vel: bool = False, privileged: bool = False
) -> tuple[str, ...]:
    """The observation's entries, in order, for a robot with ``joint_names``; ``lin_vel``: the
    base's linear velocity after them, ``privileged``: the critic's entries after those."""
    names = (
        *(f"base_ang_vel_{a}" for a in "xyz"),
        *(f"projected_gravity_{a}" for a in "xyz"),
        "command_vx", "command_vy", "command_yaw",
        *(f"{j}_pos" for j in joint_names),
        *(f"{j}_vel" for j in joint_names),
        *(f"{j}_last_action" for j in joint_names),
    )  # fmt: skip
    if lin_vel:
        names = (*names, *LIN_VEL_NAMES)
    if privileged:
        names = (*names, *privileged_names(joint_names))
    return names


LIN_VEL_NAMES = tuple(f"base_lin_vel_{a}" for a in "xyz")
PRIVILEGED_PREFIX = "privileged_"  # the critic's entries: the actor does not see them


def privileged_names(joint_names: Sequence[str]) -> tuple[str, ...]:
    """The critic's privileged entries (MuJoCo Playground's Go1 joystick ``privileged_state``
    beside the actor's noisy one): the noise-free gyro, gravity, linear velocity, joint
    positions (minus the nominal pose) and velocities, the joint torques, the feet's contact
    flags, horizontal speeds (world frame) and air times."""
    p = PRIVILEGED_PREFIX
    return (
        *(f"{p}base_ang_vel_{a}" for a in "xyz"),
        *(f"{p}projected_gravity_{a}" for a in "xyz"),
        *(f"{p}base_lin_vel_{a}" for a in "xyz"),
        *(f"{p}{j}_pos" for j in joint_names),
        *(f"{p}{j}_vel" for j in joint_names),
        *(f"{p}{j}_torque" for j in joint_names),
        *(f"{p}foot{k}_contact" for k in range(4)),
        *(f"{p}foot{k}_speed_{a}" for k in range(4) for a in "xy"),
        *(f"{p}foot{k}_air_time" for k in range(4)),
    )  # fmt: skip


def actor_entries(names: Sequence[str]) -> int:
    """How many leading entries of an observation named ``names`` the actor sees: all but the
    privileged ones, which come last."""
    count = sum(1 for name in names if not name.startswith(PRIVILEGED_PREFIX))
    if any(name.startswith(PRIVILEGED_PREFIX) for name in names[:count]):
        raise ValueError("the privileged observation entries must come last")
    return count


# what stands for the base's linear velocity on a real robot, where no sensor measures it
LIN_VEL_ON_ROBOT = (
    "no sensor measures it on a robot: a state estimator's estimate of the base's linear "
    "velocity in the base frame (m/s), from the IMU and the legs' kinematics, as legged_gym's "
    "and MuJoCo Playground's deployments use"
)


def observation_sources(nominal_pose: Sequence[float], lin_vel: bool = False) -> tuple[dict, ...]:
    """Where each entry of the actor's observation comes from in the MuJoCo model's data
    (:data:`cpg_actor.deploy.export.OBSERVATION_SOURCES`): qpos 0-6 and qvel 0-5 are the free
    base's, the joints follow in joint order; ``lin_vel``: the base's linear velocity after
    them (the base frame's velocimeter, each entry with ``on_robot``: :data:`LIN_VEL_ON_ROBOT`).
    The critic's privileged entries have none: the actor does not read them."""
    nominal = [float(p) for p in nominal_pose]
    sources = (
        *({"source": "sensor", "sensor": "base_ang_vel", "index": i} for i in range(3)),
        *({"source": "projected_gravity", "quaternion": 3, "index": i} for i in range(3)),
        *({"source": "command", "index": i} for i in range(3)),
        *({"source": "qpos", "index": 7 + j, "offset": 0.0 - p} for j, p in enumerate(nominal)),
        *({"source": "qvel", "index": 6 + j} for j in range(len(nominal))),
        *({"source": "desired", "index": j, "offset": 0.0 - p} for j, p in enumerate(nominal)),
    )  # fmt: skip
    if lin_vel:
        sources = (*sources, *({"source": "sensor", "sensor": "base_lin_vel", "index": i,
                                "on_robot": LIN_VEL_ON_ROBOT} for i in range(3)))  # fmt: skip
    return sources


def sensor_noise(num_joints: int) -> np.ndarray:
    """The sensors' noise, std per observation entry (a perturbation's ``obs_noise`` = 1):
    legged_gym's noise scales (Rudin et al. 2021), there uniform, here Gaussian: gyro 0.2
    rad/s, projected gravity 0.05, joint encoders 0.01 rad, joint speeds 1.5 rad/s; the
    command and the last action carry none."""
    j = num_joints
    return np.concatenate([np.full(3, 0.2), np.full(3, 0.05), np.zeros(3), np.full(j, 0.01),
                           np.full(j, 1.5), np.zeros(j)])  # fmt: skip


NOISE_GROUPS = ("gyro", "gravity", "joint_pos", "joint_vel", "lin_vel")  # observation_noise's


def noise_half_widths(widths: dict, num_joints: int, lin_vel: bool) -> np.ndarray:
    """Per entry of the actor's observation (the privileged entries carry none), the half-width
    of the uniform noise added at every step (MuJoCo Playground's ``noise_config``:
    ``x + U(-1, 1) w``): ``widths`` maps each of :data:`NOISE_GROUPS` to ``w`` (absent: 0); the
    command and the last action carry none."""
    j = num_joints
    w = {name: float(widths.get(name, 0.0)) for name in NOISE_GROUPS}
    parts = [np.full(3, w["gyro"]), np.full(3, w["gravity"]), np.zeros(3),
             np.full(j, w["joint_pos"]), np.full(j, w["joint_vel"]), np.zeros(j)]  # fmt: skip
    if lin_vel:
        parts.append(np.full(3, w["lin_vel"]))
    return np.concatenate(parts)


def uniform_noise(unit_draws, half_widths):
    """``unit_draws`` (N, D) uniform in [-1, 1) scaled to ``half_widths`` (D,): the noise
    :func:`noise_half_widths` describes."""
    return unit_draws * half_widths


def rotate_to_world(quat, vectors):
    """(N, 3): ``vectors`` (N, 3) given in the base frame, in the world frame, by the base
    quaternion (w, x, y z): ``R v``."""
    xp = namespace(quat)
    w, x, y, z = (quat[:, i] for i in range(4))
    vx, vy, vz = (vectors[:, i] for i in range(3))
    rows = (
        (1 - 2 * (y * y + z * z)) * vx + 2 * (x * y - w * z) * vy + 2 * (x * z + w * y) * vz,
        2 * (x * y + w * z) * vx + (1 - 2 * (x * x + z * z)) * vy + 2 * (y * z - w * x) * vz,
        2 * (x * z - w * y) * vx + 2 * (y * z + w * x) * vy + (1 - 2 * (x * x + y * y)) * vz,
    )
    return xp.stack(rows, axis=1)


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


STILL = 0.01  # MuJoCo Playground's zero command: |(vx, vy, yaw)| below this


def field_terms(
    quat, lin_vel, ang_vel, command, joint_pos, joint_vel, torque, terminated, feet_z,
    feet_speed, contact, touchdown, air_time, swing_peak, nominal, pose_weights, joint_range,
    max_foot_height: float, air_time_target: float,
) -> dict[str, np.ndarray]:  # fmt: skip
    """MuJoCo Playground's Go1 joystick terms (``go1/joystick.py``, version 0.2.0) that
    :func:`reward_terms` does not hold as Playground defines them, (N,) each, unscaled.

    ``quat`` the base's (w, x, y, z); ``lin_vel``, ``ang_vel`` in the base frame;
    ``joint_pos`` and ``nominal`` (J,) rad, ``pose_weights`` (J,); ``joint_range`` a pair of
    (J,) soft limits (rad) or None (no limit term: 0); ``feet_z`` (N, 4) m, ``feet_speed``
    (N, 4, 2) their horizontal velocity (world, m/s); ``contact`` and ``touchdown`` (N, 4)
    bool, a touchdown a foot in contact after time in the air; ``air_time`` (N, 4) s of the
    feet's time in the air this step included; ``swing_peak`` (N, 4) m the highest each foot
    rose since it last touched the ground. A command counts as zero below :data:`STILL`.
    """
    xp = namespace(lin_vel)
    moving = xp.sqrt(xp.sum(command**2, 1)) > STILL
    offset = joint_pos - nominal
    world_vel, world_rate = rotate_to_world(quat, lin_vel), rotate_to_world(quat, ang_vel)
    speed_sq = xp.sum(feet_speed**2, -1)  # (N, 4)
    if joint_range is None:
        beyond = xp.zeros_like(joint_pos)
    else:
        low, high = joint_range
        beyond = xp.maximum(low - joint_pos, 0.0) + xp.maximum(joint_pos - high, 0.0)
    return {
        "lin_vel_z_world": world_vel[:, 2] ** 2,  # v_z^2, world frame
        "ang_vel_xy_world": xp.sum(world_rate[:, :2] ** 2, 1),  # w_x^2 + w_y^2, world frame
        "torque_norms": xp.sqrt(xp.sum(torque**2, 1)) + xp.sum(xp.abs(torque), 1),
        "energy": xp.sum(xp.abs(joint_vel) * xp.abs(torque), 1),  # W, |qdot| |tau| summed
        "pose": xp.exp(-xp.sum(offset**2 * pose_weights, 1)),
        "stand_still": xp.sum(xp.abs(offset), 1) * ~moving,
        "termination": terminated.astype(lin_vel.dtype),
        "dof_pos_limits": xp.sum(beyond, 1),  # rad beyond the soft limits
        "feet_slip_commanded": xp.sum(speed_sq * contact, 1) * moving,
        "feet_clearance": xp.sum(xp.abs(feet_z - max_foot_height) * speed_sq**0.25, 1),
        "feet_height": xp.sum((swing_peak / max_foot_height - 1.0) ** 2 * touchdown, 1) * moving,
        "feet_air_time_commanded": xp.sum((air_time - air_time_target) * touchdown, 1) * moving,
    }


# every reward term a config may scale: reward_terms' and field_terms'
TERMS = (
    "tracking_lin_vel", "tracking_ang_vel", "lin_vel_z", "ang_vel_xy", "orientation",
    "base_height", "torques", "joint_acc", "action_rate", "feet_air_time", "feet_slip",
    "lin_vel_z_world", "ang_vel_xy_world", "torque_norms", "energy", "pose", "stand_still",
    "termination", "dof_pos_limits", "feet_slip_commanded", "feet_clearance", "feet_height",
    "feet_air_time_commanded",
)  # fmt: skip


def privileged_observation(ang_vel, gravity, lin_vel, joint_offset, joint_vel, torque, contact,
                           feet_speed, air_time):  # fmt: skip
    """(N, len(privileged_names)) the critic's entries, noise-free, in the order of
    :func:`privileged_names`."""
    xp = namespace(ang_vel)
    n = ang_vel.shape[0]
    return xp.concatenate(
        [ang_vel, gravity, lin_vel, joint_offset, joint_vel, torque,
         contact.astype(ang_vel.dtype), feet_speed.reshape(n, 8), air_time], axis=1,
    )  # fmt: skip


def clip_reward(reward, low):
    """The step's reward clipped below at ``low`` (None: as it is)."""
    if low is None:
        return reward
    return namespace(reward).maximum(reward, low)


def base_yaw(quat):
    """(N,) rad: the heading of the base's x axis in the world's plane, from its quaternion
    (w, x, y, z), in (-pi, pi]."""
    xp = namespace(quat)
    w, x, y, z = (quat[:, i] for i in range(4))
    return xp.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def heading_yaw_rate(quat, heading, gain: float, low: float, high: float):
    """(N,) rad/s: legged_gym's heading command, the yaw rate that turns the base toward
    ``heading`` (N,) rad, ``gain`` x (heading - yaw) wrapped to [-pi, pi), clipped to
    [``low``, ``high``]."""
    xp = namespace(quat)
    error = (heading - base_yaw(quat) + xp.pi) % (2 * xp.pi) - xp.pi
    return xp.clip(gain * error, low, high)


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
    swing_peak: Any  # (N, 4) m: the highest each foot rose since it last touched the ground


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
        swing_peak=xp.zeros((n, 4), dtype=joints.dtype),
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


def observe(qpos, qvel, ang_vel, command, last_action, nominal, lin_vel=None, privileged=None):
    """:func:`observation` of the state after a step (non-finite entries 0), with the base's
    linear velocity ``lin_vel`` (N, 3) and the critic's ``privileged`` entries
    (:func:`privileged_observation`) after it where given."""
    xp = namespace(qpos)
    obs = observation(ang_vel, projected_gravity(qpos[:, 3:7]), command, qpos[:, 7:],
                      qvel[:, 6:], last_action, nominal)  # fmt: skip
    extra = [part.astype(obs.dtype) for part in (lin_vel, privileged) if part is not None]
    if extra:
        obs = xp.concatenate([obs, *extra], axis=1)
    return xp.nan_to_num(obs, nan=0.0, posinf=0.0, neginf=0.0)


def step(config, episode: Episode, reading: Reading, desired, nominal, foot_radius: float,
         weight: float, joint_range=None) -> tuple[Episode, dict]:  # fmt: skip
    """One control step of the task: ``(episode, outputs)``, the episode after the step (not
    yet restarted where it ended) and ``obs`` (the step's last observation), ``reward``,
    ``reward_terms`` (scaled), ``terminated``, ``truncated``, ``episode_metrics`` (NaN for
    the robots whose episode goes on) and ``info`` (``command``, ``contact``,
    ``base_height``, ``forward_speed``, ``desired_position``, ``measured_position``,
    ``measured_velocity``, ``joint_torque`` (N, J, N m) and ``foot_position`` (N, 4, 3, the
    feet in the world, m): the physical metrics' inputs).

    ``config``: the env's (scales, sigma, fall limits, steps, the recipe's options: the
    observation's linear velocity and privileged entries, the action scale of the action
    rate, the reward's clip); ``desired`` (N, J) the positions the step tracked; ``nominal``
    (J,) the nominal pose; ``weight`` m g (N), the cost of transport's; ``joint_range`` the
    soft joint limits of the ``dof_pos_limits`` term, a pair of (J,) arrays (None: no such
    term is paid)."""
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
    # the action rate in the action's own units where actions are nominal + scale x a
    unit = config.action_scale or 1.0
    terms = reward_terms(
        lin_vel, ang_vel, gravity, height, episode.command, reading.torque, joint_acc,
        desired / unit, episode.last_action / unit, air_paid, slip, config.tracking_sigma,
        config.base_height_target,
    )  # fmt: skip
    terminated = (fallen(height, gravity, config.fall_height, config.fall_tilt)
                  | reading.base_touch | unstable)  # fmt: skip
    feet_speed = (feet[:, :, :2] - episode.feet_xy) / dt  # world frame, over the step
    swing_peak = xp.maximum(episode.swing_peak, feet[:, :, 2])
    if set(config.reward_scales) - set(terms):  # a field term is scaled: compute them
        terms.update(field_terms(
            qpos[:, 3:7], lin_vel, ang_vel, episode.command, qpos[:, 7:], joint_vel,
            reading.torque, terminated, feet[:, :, 2], feet_speed, contact, touchdown, air_time,
            swing_peak, nominal, xp.asarray(config.leg_pose_weights * 4), joint_range,
            config.max_foot_height, config.air_time_target,
        ))  # fmt: skip
    scaled = {name: xp.where(unstable, 0.0, value * config.reward_scales[name] * dt)
              for name, value in terms.items() if name in config.reward_scales}  # fmt: skip
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
        swing_peak=xp.where(contact, 0.0, swing_peak),
    )  # fmt: skip
    truncated = (after.elapsed >= config.episode_steps) & ~terminated
    done = terminated | truncated
    privileged = None
    if config.privileged_observation:
        privileged = privileged_observation(ang_vel, gravity, lin_vel, qpos[:, 7:] - nominal,
                                            joint_vel, reading.torque, contact, feet_speed,
                                            air_time)  # fmt: skip
    obs = observe(qpos, qvel, ang_vel, episode.command, desired, nominal,
                  lin_vel if config.observe_lin_vel else None, privileged)  # fmt: skip
    outputs = {
        "obs": xp.where(unstable[:, None], xp.zeros_like(obs), obs),
        "reward": clip_reward(sum(scaled.values()), config.reward_clip_min),
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
