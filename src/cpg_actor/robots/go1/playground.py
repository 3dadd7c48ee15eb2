"""MuJoCo Playground's Go1 joystick recipe, its env side: the values of ``Go1Config`` that
``--preset playground`` sets (``Go1Config.PLAYGROUND``; the PPO side is the preset's,
:mod:`cpg_actor.config.presets`).

Source: the ``playground`` package 0.2.0, ``mujoco_playground/_src/locomotion/go1/``
(``joystick.py``'s ``default_config`` and its step, ``base.py``, ``randomize.py``) for
Go1JoystickFlatTerrain. Where this codebase runs it otherwise (``docs/go1.md``, "MuJoCo
Playground's recipe"):

* physics 5 ms x 4 substeps (Playground: 4 ms x 5), the same 20 ms control step, as every
  agent on the Go1 here;
* the project's Go1 model and actuator law: Kp and Kd are Playground's, but the derivative
  term is the drive's (Playground: the joints' passive damping set to Kd), the joints keep
  Menagerie's passive damping, armature and friction loss, and the drives their torque-speed
  limit; the nominal pose has abduction 0 (Playground's home: +-0.1 rad);
* a fall is a base tilted past 90 degrees (Playground's up-vector below the horizon) or whose
  centre is within 1 cm of the ground (Playground has no height limit);
* the start: the nominal pose at rest, heading along x (Playground also shifts the start by
  +-0.5 m, turns it to a uniform heading and gives the base a velocity of U(-0.5, 0.5) per
  axis);
* the domain randomisation drawn per episode (Playground: once per env), of its terms the
  ones this env draws: floor friction U(0.4, 1.0), armature x U(1.0, 1.05) and the torso's
  added mass, its non-negative half U(0, 1) kg (not its link masses x U(0.9, 1.1), the
  torso's centre of mass +-5 cm, the joints' friction loss x U(0.9, 1.1) or the zero pose);
* the feet's speed (feet_slip, feet_clearance, the privileged entries) is their displacement
  over the control step (Playground: a velocity sensor at the foot).
"""

from __future__ import annotations

import math
from typing import Any

# every reward term's scale, per second (the sum times the control step, then clipped at 0).
# Playground's terms whose definition differs from the project's term of the same name are
# this project's *_world, torque_norms, feet_slip_commanded and feet_air_time_commanded
# (cpg_actor.tasks.velocity.field_terms); the project's own terms are 0
REWARD_SCALES: dict[str, float] = {
    "tracking_lin_vel": 1.0,
    "tracking_ang_vel": 0.5,
    "lin_vel_z_world": -0.5,  # Playground's lin_vel_z (the world frame's v_z)
    "ang_vel_xy_world": -0.05,  # Playground's ang_vel_xy (world frame)
    "orientation": -5.0,
    "dof_pos_limits": -1.0,
    "pose": 0.5,
    "termination": -1.0,
    "stand_still": -1.0,
    "torque_norms": -2e-4,  # Playground's torques: |tau|_2 + |tau|_1
    "action_rate": -0.01,
    "energy": -1e-3,
    "feet_clearance": -2.0,
    "feet_height": -0.2,
    "feet_slip_commanded": -0.1,  # Playground's feet_slip
    "feet_air_time_commanded": 0.1,  # Playground's feet_air_time
    # the project's legged_gym terms, not Playground's
    "lin_vel_z": 0.0,
    "ang_vel_xy": 0.0,
    "base_height": 0.0,
    "torques": 0.0,
    "joint_acc": 0.0,
    "feet_air_time": 0.0,
    "feet_slip": 0.0,
}

PLAYGROUND: dict[str, Any] = {
    "kp": 35.0,  # default_config Kp (N m/rad)
    "kd": 0.5,  # default_config Kd (N m s/rad)
    "action_scale": 0.5,  # default_config action_scale: target = home + 0.5 a, a in [-1, 1]
    "episode_seconds": 20.0,  # episode_length 1000 x ctrl_dt 0.02
    "floor_contacts": "feet",  # its feet-only flat scene
    "reset_noise": 0.0,  # it starts in the home keyframe exactly
    "fall_tilt": math.pi / 2,  # _get_termination: the up-vector's z below 0
    "fall_height": 0.01,  # none in Playground (above)
    "tracking_sigma": 0.25,  # reward_config.tracking_sigma
    "max_foot_height": 0.1,  # reward_config.max_foot_height (m)
    "air_time_target": 0.1,  # _reward_feet_air_time: air time - 0.1 s
    "leg_pose_weights": (1.0, 1.0, 0.1),  # _reward_pose
    "soft_joint_limit_factor": 0.95,  # default_config soft_joint_pos_limit_factor
    "reward_scales": REWARD_SCALES,
    "reward_clip_min": 0.0,  # step: clip(sum x dt, 0, 10000)
    "observe_lin_vel": True,  # _get_obs: the state starts with the local linear velocity
    "privileged_observation": True,  # the critic's privileged_state (locomotion_params)
    # noise_config (level 1): uniform, x + U(-1, 1) x scale
    "observation_noise": {
        "joint_pos": 0.03,
        "joint_vel": 1.5,
        "gyro": 0.2,
        "gravity": 0.05,
        "lin_vel": 0.1,
    },  # fmt: skip
    # command_config: a, the commands' amplitudes (uniform in [-a, a]); b, the probability
    # that a resampled entry is not zeroed; sample_command keeps an entry with probability
    # 0.5; the time to the next command exponential of mean 5 s
    "command_range": (-1.5, 1.5),
    "lateral_range": (-0.8, 0.8),
    "yaw_range": (-1.2, 1.2),
    "command_nonzero": (0.9, 0.25, 0.5),
    "command_hold": 0.5,
    "command_resample_seconds": 5.0,
    "command_interval": "exponential",
    "standing_share": 0.0,  # the first command of an episode is never zeroed
    # randomize.py, the terms this env draws (above)
    "randomize": {"friction": (0.4, 1.0), "armature": (1.0, 1.05), "payload": (0.0, 1.0)},
}
