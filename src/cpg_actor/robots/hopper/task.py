"""The hopper's task, written once for every simulator: the start pose, and what a control step
gives once the physics has run (observation, reward eq. 4 or the apex reward, blow-up
termination, truncation, the step's info, the episode's hop height).

Pure functions of batched arrays (N robots): numpy (float64) in the MuJoCo and PyBullet
simulation (:mod:`cpg_actor.robots.hopper.simulation`), ``jax.numpy`` inside the MJX env's
jitted step (:mod:`cpg_actor.robots.hopper.mjx.dynamics`); the module of the inputs is used
(:mod:`cpg_actor.robots.common.array_namespace`). Only the physics differs between them.
Masks are ``where``, never Python branches on values, so that JAX can trace them.
"""

from __future__ import annotations

import numpy as np

from cpg_actor.robots.anymal_leg import kinematics as leg_kinematics
from cpg_actor.robots.common.array_namespace import as_float, namespace
from cpg_actor.robots.hopper import description as robot
from cpg_actor.robots.hopper import kinematics
from cpg_actor.robots.hopper.reward import apex_reward, reward_terms, total_reward

OBS_NAMES = (
    "p_m_HFE",  # measured joint positions, rad
    "p_m_KFE",
    "v_m_HFE",  # measured joint velocities, rad/s
    "v_m_KFE",
    "p_d_HFE",  # desired joint positions being tracked (the last action, filtered), rad
    "p_d_KFE",
    "hip_height",  # m, height of the hip (HFE axis) above the ground
    "hip_velocity",  # m/s, vertical, positive up
)
# where each entry comes from in the MuJoCo model's data
# (cpg_actor.deploy.export.OBSERVATION_SOURCES)
OBS_SOURCES = (
    {"source": "qpos", "index": 1},
    {"source": "qpos", "index": 2},
    {"source": "qvel", "index": 1},
    {"source": "qvel", "index": 2},
    {"source": "desired", "index": 0},
    {"source": "desired", "index": 1},
    {"source": "qpos", "index": 0},  # the rail joint's position is the hip height
    {"source": "qvel", "index": 0},
)
# the sensors' noise, std per observation entry (perturbation.obs_noise = 1): legged_gym's noise
# scales (Rudin et al. 2021) for joint encoders (0.01 rad) and joint speeds (1.5 rad/s),
# there uniform, here Gaussian; the command sent and the rail's readings carry none
SENSOR_NOISE = (0.01, 0.01, 1.5, 1.5, 0.0, 0.0, 0.0, 0.0)
NOMINAL_POSE = np.array(robot.NOMINAL_POSE)
ACTION_LOW = np.array([robot.JOINT_LIMITS[j][0] for j in robot.JOINT_NAMES])
ACTION_HIGH = np.array([robot.JOINT_LIMITS[j][1] for j in robot.JOINT_NAMES])
OBS_BOUND = 1e6  # finite stand-in for non-finite values of a blown-up simulation


def desired_positions(actions, normalized: bool):
    """Actions to desired joint positions within the joint limits: the actions are the
    positions (rad), or with ``normalized`` in [-1, 1] from the lower to the upper limit."""
    xp = namespace(actions)
    low, high = as_float(xp, ACTION_LOW), as_float(xp, ACTION_HIGH)
    if normalized:
        actions = low + (xp.clip(actions, -1.0, 1.0) + 1.0) * (high - low) / 2.0
    # the float32 action space's bounds: a position within them is a valid action
    return xp.clip(actions, low.astype(xp.float32), high.astype(xp.float32))


def command_filter(previous, command, alpha: float):
    """The desired positions the motors get under a first-order low-pass on the command:
    ``previous + alpha * (command - previous)`` (``previous``: the last desired positions,
    the reset's pose at an episode's first step; ``alpha`` in (0, 1], a Python number).

    Why: an agent whose command is not smooth by construction (an MLP) can be made as smooth
    as a CPG's by the env, for a comparison at matched smoothness. The filter's state is the
    last desired positions, which the observation already holds, so the task stays Markov.
    ``alpha`` = 1 is no filter: the command itself, bit for bit."""
    if alpha == 1.0:
        return command
    return previous + alpha * (command - previous)


def start_qpos(joint_noise, clearance):
    """``qpos`` ``(..., 3)`` (hip height, HFE, KFE) of a robot at rest in the nominal pose plus
    ``joint_noise`` ``(..., 2)``, the lowest point of its foot ``clearance`` above the ground."""
    xp = namespace(joint_noise)
    joint = as_float(xp, NOMINAL_POSE) + joint_noise
    hip = kinematics.standing_hip_height(joint) + clearance
    return xp.concatenate([hip[..., None], joint], axis=-1)


def observation(qpos, qvel, desired):
    """(N, 8) float32 in the order of :data:`OBS_NAMES`, non-finite values clipped to
    +-``OBS_BOUND``."""
    xp = namespace(qpos)
    obs = xp.concatenate([qpos[:, 1:3], qvel[:, 1:3], desired, qpos[:, 0:1], qvel[:, 0:1]], 1)
    obs = xp.nan_to_num(obs, nan=0.0, posinf=OBS_BOUND, neginf=-OBS_BOUND)
    return xp.clip(obs, -OBS_BOUND, OBS_BOUND).astype(xp.float32)


def foot_height(qpos):
    """(N,) height of the lowest point of the foot sphere above the ground (0: touching)."""
    return qpos[:, 0] + leg_kinematics.foot_position(qpos[:, 1:3])[:, 1] - robot.FOOT_RADIUS


def com_velocity(qpos, qvel):
    """(N,) vertical velocity of the robot's centre of mass (the apex reward's)."""
    return kinematics.com_vertical_velocity(qvel[:, 0], qpos[:, 1:3], qvel[:, 1:3])


def blown_up(config, qpos, qvel):
    """(N,) bool: non-finite state or absurd velocities."""
    xp = namespace(qpos)
    bad = ~xp.isfinite(qpos).all(axis=1) | ~xp.isfinite(qvel).all(axis=1)
    bad |= xp.abs(qvel[:, 1:3]).max(axis=1) > config.blowup_joint_velocity
    bad |= xp.abs(qvel[:, 0]) > config.blowup_hip_velocity
    return bad


def step_outcome(config, qpos, qvel, desired, torque, elapsed, episode_steps,
                 com_velocity_before=None, unstable=False) -> dict:  # fmt: skip
    """What a control step gives, from the state after it (``qpos``, ``qvel``), the desired
    positions tracked (N, 2), the joint torque (N, 2, mean over the step) and the episode
    clocks ``elapsed`` (N,) counting this step. ``com_velocity_before``: :func:`com_velocity`
    before the step (needed by ``hop_reward="apex"``); ``unstable``: (N,) robots the simulator
    itself gave up on. A blown-up robot is terminated with zero reward and finite numbers.

    Keys: ``obs``, ``reward``, ``terminated``, ``truncated``, ``reward_terms`` and the step's
    info ``hip_height``, ``foot_height``, ``joint_torque``, ``desired_position``,
    ``measured_position``, ``measured_velocity`` and ``foot_position`` (N, 1, 3: the foot
    sphere's centre in the world, x along the ground, y 0, z up; the physical metrics' foot
    slip)."""
    xp = namespace(qpos)
    foot_vx = leg_kinematics.foot_velocity(qpos[:, 1:3], qvel[:, 1:3])[:, 0]
    foot_velocity_xy = xp.stack([foot_vx, xp.zeros_like(foot_vx)], -1)  # the hip is on a rail
    terms = reward_terms(config.reward_weights, qvel[:, 0], desired, qpos[:, 1:3], qvel[:, 1:3],
                         torque, foot_velocity_xy)  # fmt: skip
    feet = foot_height(qpos)
    if config.hop_reward == "apex":
        com_height = qpos[:, 0] + kinematics.com_height_offset(qpos[:, 1:3])
        terms["r1"] = apex_reward(config.apex_weight, com_velocity_before,
                                  com_velocity(qpos, qvel), com_height,
                                  kinematics.highest_standing_com(), feet)  # fmt: skip
    terminated = blown_up(config, qpos, qvel) | unstable
    terms = {name: xp.where(terminated, 0.0, value) for name, value in terms.items()}

    def finite(value):  # a blown-up robot's numbers clipped to finite ones
        clean = xp.clip(xp.nan_to_num(value), -OBS_BOUND, OBS_BOUND)
        return xp.where(terminated.reshape((-1,) + (1,) * (value.ndim - 1)), clean, value)

    return {
        "obs": observation(qpos, qvel, desired),
        "reward": total_reward(terms),
        "terminated": terminated,
        "truncated": (elapsed >= episode_steps) & ~terminated,
        "reward_terms": terms,
        "hip_height": finite(qpos[:, 0]),
        "foot_height": finite(feet),
        "joint_torque": finite(torque),
        "desired_position": desired,
        "measured_position": finite(qpos[:, 1:3]),
        "measured_velocity": finite(qvel[:, 1:3]),
        "foot_position": finite(foot_world(qpos))[:, None, :],
    }


def foot_world(qpos):
    """(N, 3) the foot sphere's centre in the world (m): x along the ground (the hip's rail at
    x = 0), y = 0 (the leg is planar), z up."""
    xp = namespace(qpos)
    foot = leg_kinematics.foot_position(qpos[:, 1:3])
    return xp.stack([foot[:, 0], xp.zeros_like(foot[:, 0]), qpos[:, 0] + foot[:, 1]], axis=-1)


def hop_height(done, max_hip, standing):
    """(N,) an ended episode's highest hip height above the one it started at (m, >= 0); NaN
    for the envs still running."""
    xp = namespace(max_hip)
    return xp.where(done, xp.maximum(0.0, max_hip - standing), xp.nan)
