"""legged_gym's ANYmal B recipe, its env side: the values of ANYmal B's env config
(``QuadrupedConfig.LEGGED_GYM``, whose numbers are ANYmal B's) that ``--preset legged_gym`` sets
(the PPO side is the preset's, :data:`cpg_actor.config.presets.LEGGED_GYM`).

Source: leggedrobotics/legged_gym (commit 8fa29ac), ``legged_gym/envs/base/legged_robot.py``
(the step, rewards, observation, noise, commands, resets, pushes, terminations) and
``legged_robot_config.py`` (``LeggedRobotCfg``), under ANYmal B's registered task
``anymal_b``: ``AnymalBRoughCfg``, which changes nothing of ``AnymalCRoughCfg``
(``anymal_c/mixed_terrains/anymal_c_rough_config.py``) but the robot's file.

Flat ground. legged_gym's ANYmal B task is its rough one (a trimesh with a height scan); this
project's ANYmal task is flat, so the terrain is the plane without a height scan, the two
terrain changes ``AnymalCFlatCfg`` makes (``anymal_c/flat/anymal_c_flat_config.py``), and
nothing else of that config: its other changes (orientation -5, torques -2.5e-5,
feet_air_time 2, no heading command, commands every 4 s, yaw rate +-1.5, friction 0-1.5, a
128-64-32 network, 300 iterations) are a short demo tuned on another robot, ANYmal C. On a
plane legged_gym also turns the terrain curriculum off and its height-scan terms vanish.

Where this codebase runs it otherwise (``docs/quadruped.md``, "legged_gym's recipe"):

* the drives: this project's ANYmal B actuator law (PD Kp 80, Kd 2 as legged_gym's, clipped
  at 40 N m with the 15 rad/s torque-speed line) where legged_gym's ANYmal runs an actuator
  network (``anydrive_v3_lstm.pt``, ``use_actuator_network``) and its URDF says 80 N m; the
  model's joint stops (nominal +-0.9 rad, HAA +-0.6; the URDF: +-9.42);
* actions a clipped to [-1, 1]: targets within the nominal pose +- 0.5 rad (legged_gym clips
  a at +-100, ``clip_actions``);
* MuJoCo at 5 ms x 4 (PhysX at 5 ms x 4 in legged_gym): the same 20 ms control step;
* the collision term (-1, thighs and shanks touching): this model's thighs and shanks have no
  collision shapes (the base box and the feet are its only), so the term would be 0 and is
  not paid; legged_gym's feet contact is a force above 1 N filtered over two steps, here a
  foot within 5 mm of the ground (``feet_air_time``);
* the termination term: legged_gym adds it after the clip, but ANYmal's scale is 0: none;
* the start: the feet placed on the ground (legged_gym drops the base from 0.6 m); the first
  step's action rate measured from the start pose (legged_gym: from a = 0);
* the heading command's yaw rate recomputed after a step, so a step's reward is paid under
  the command its action saw (legged_gym: under the one recomputed after the step);
* randomisation drawn per episode (legged_gym: friction once per env, in 64 buckets, and the
  base mass at creation): the effective friction U(0.75, 1.125) (legged_gym's U(0.5, 1.25) on
  the robot, averaged by PhysX with the plane's 1.0, as ``anymal_c_flat_config.py`` notes);
  the added base mass, its non-negative half U(0, 5) kg (legged_gym: U(-5, 5)); a push 15 s
  into each episode, a kick of U(0, 1) m/s in a random direction added to the base's
  horizontal velocity (legged_gym: every 15 s of the run's clock, the velocity set to
  U(-1, 1) per axis).
"""

from __future__ import annotations

import math
from typing import Any

# every reward term's scale, per second (the sum times the control step, then clipped at 0):
# LeggedRobotCfg.rewards.scales, which AnymalCRoughCfg and AnymalBRoughCfg keep. The project's
# terms are legged_gym's (tasks/velocity.py, reward_terms): joint_acc is its dof_acc, the
# others keep their names; orientation and base_height are the project's additions, 0 here
REWARD_SCALES: dict[str, float] = {
    "tracking_lin_vel": 1.0,
    "tracking_ang_vel": 0.5,
    "lin_vel_z": -2.0,
    "ang_vel_xy": -0.05,
    "orientation": 0.0,  # -0. in LeggedRobotCfg
    "base_height": 0.0,  # -0.
    "torques": -1e-5,  # -0.00001
    "joint_acc": -2.5e-7,  # dof_acc
    "action_rate": -0.01,
    "feet_air_time": 1.0,  # (air time - 0.5 s) at touchdown, under |command_xy| > 0.1
    "feet_slip": 0.0,  # not a legged_gym term
}

LEGGED_GYM: dict[str, Any] = {
    # AnymalCRoughCfg.control: stiffness, damping, action_scale, decimation; LeggedRobotCfg.sim
    "kp": 80.0,  # N m/rad
    "kd": 2.0,  # N m s/rad
    "action_scale": 0.5,  # target = default + 0.5 a
    "physics_dt": 0.005,  # sim.dt
    "decimation": 4,  # control at 50 Hz
    "episode_seconds": 20.0,  # env.episode_length_s
    "reward_scales": REWARD_SCALES,
    "reward_clip_min": 0.0,  # rewards.only_positive_rewards: the sum clipped at 0
    "tracking_sigma": 0.25,  # rewards.tracking_sigma
    "base_height_target": 0.5,  # AnymalCRoughCfg.rewards (its term's scale is 0)
    "soft_joint_limit_factor": 1.0,  # rewards.soft_dof_pos_limit (its term is not paid)
    # compute_observations: base linear velocity first (the critic sees the actor's
    # observation: num_privileged_obs None)
    "observe_lin_vel": True,
    "privileged_observation": False,
    # noise.noise_scales at noise_level 1, uniform (2 U(0, 1) - 1) x scale: _get_noise_scale_vec
    # multiplies each by its obs scale and adds it to the scaled entry, the same noise in the
    # entry's own units as these
    "observation_noise": {
        "lin_vel": 0.1,
        "gyro": 0.2,
        "gravity": 0.05,
        "joint_pos": 0.01,
        "joint_vel": 1.5,
    },  # fmt: skip
    # commands: ranges lin_vel_x, lin_vel_y; heading_command with heading U(-3.14, 3.14), the
    # yaw rate clip(0.5 wrap(heading - yaw), -1, 1); resampling_time 10 s; a drawn (vx, vy) of
    # norm 0.2 or less zeroed (_resample_commands)
    "command_range": (-1.0, 1.0),
    "lateral_range": (-1.0, 1.0),
    "yaw_range": (-1.0, 1.0),  # ang_vel_yaw, the heading's clip
    "heading_gain": 0.5,
    "heading_range": (-3.14, 3.14),
    "min_command_speed": 0.2,
    "command_resample_seconds": 10.0,
    "command_interval": "fixed",
    "standing_share": 0.0,
    "command_nonzero": None,
    # _reset_dofs: default x U(0.5, 1.5) per joint at rest; _reset_root_states: each of the
    # base's six velocities U(-0.5, 0.5), heading along x
    "reset_noise": 0.0,
    "reset_joint_scale": (0.5, 1.5),
    "reset_base_velocity": 0.5,
    # check_termination: base contact alone (terminate_after_contacts_on ["base"]); no fall
    # by height or tilt (the base touches the ground first)
    "fall_tilt": math.pi,
    "fall_height": 0.01,
    # domain_rand (above): friction, added base mass, pushes every 15 s up to 1 m/s
    "randomize": {
        "friction": (0.75, 1.125),
        "payload": (0.0, 5.0),
        "push_velocity": (0.0, 1.0),
        "push_interval": (15.0, 15.0),
    },
}
