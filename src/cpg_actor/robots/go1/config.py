"""`Go1Config`: the quadruped locomotion task (:class:`QuadrupedConfig`) with the Go1's numbers
where its body differs from ANYmal B's, each with its reason."""

from __future__ import annotations

from dataclasses import dataclass, field

from cpg_actor.robots.common.quadruped.config import QuadrupedConfig, default_scales
from cpg_actor.robots.go1 import description as robot
from cpg_actor.robots.go1.playground import PLAYGROUND


def _go1_scales() -> dict[str, float]:
    # the torque penalty of legged_gym's A1 (Rudin et al. 2021; the Go1's sibling, of the same
    # torque range): -2e-4 per (N m)^2 s; ANYmal's -1e-5 hardly weighs on the Go1's smaller torques
    return {**default_scales(), "torques": -2e-4}


@dataclass
class Go1Config(QuadrupedConfig):
    """The Unitree Go1 locomotion task (``docs/go1.md``); unlisted fields are ANYmal's
    (:class:`QuadrupedConfig`'s, ``docs/quadruped.md``)."""

    # The project's actuator law (cpg_actor.robots.common.actuator) per joint of a leg
    # (abduction, hip, knee). kp: Menagerie's position actuators' 100 N m/rad. kd: 1 N m s/rad,
    # which with the joints' passive damping (2 on hip and knee) damps the hip and knee about
    # critically (sqrt(kp I) * 2 ~ 3 N m s/rad for the ~0.02 kg m^2 each moves, armature
    # included). Torque limits: the Go1's (description.TORQUE_LIMITS, Menagerie's forcerange).
    kp: float | tuple[float, ...] = 100.0
    kd: float | tuple[float, ...] = 1.0
    torque_limit: float | tuple[float, ...] = tuple(
        robot.TORQUE_LIMITS[k] for k in robot.JOINT_KINDS
    )
    # The joint speed limit (the torque-speed line's no-load speed). The MJCF gives none; these
    # are the velocity limits mjlab gives its Go1 actuators (mujocolab/mjlab,
    # asset_zoo/robots/unitree_go1/go1_constants.py: 30.1 rad/s for the abduction and hip
    # drives, 20.06 rad/s for the knee, whose gearbox is 1.5 times the hip's). That file does
    # not say where 30.1 comes from; reading it as the motor's no-load output speed is an
    # assumption. So is the stall torque, twice the torque limit (ANYmal's proportion; no
    # torque-speed curve of the Go1's motor was at hand): the full torque is there up to half
    # the no-load speed.
    velocity_limit: float | tuple[float, ...] = (30.1, 30.1, 20.06)
    saturation_torque: float | tuple[float, ...] = tuple(
        2.0 * robot.TORQUE_LIMITS[k] for k in robot.JOINT_KINDS
    )
    # 5 ms x 4 substeps (legged_gym's sim step): the same 20 ms control step as ANYmal's 2 ms
    # x 10 with 2.5x fewer substeps, chosen after training on each step and measuring tracking
    # and transfer (benchmarks/quadruped_physics_training.py; docs/go1.md). 4 ms x 5 did as
    # well, but its substeps do not divide the latencies of the robustness suite and of the
    # field's randomisation (0.5 and 1.5 control steps)
    physics_dt: float = 0.005
    decimation: int = 4
    foot_friction: float = robot.FOOT_FRICTION  # Menagerie's feet
    base_height_target: float = 0.27  # m: Menagerie's home keyframe (the nominal pose stands there)
    fall_height: float = 0.14  # m: about half the standing height, as ANYmal's 0.25 of 0.48
    reward_scales: dict[str, float] = field(default_factory=_go1_scales)

    moving_mass = robot.TOTAL_MASS  # kg: sizes its payloads and pushes (QuadrupedConfig's)
    # randomised training's ranges for the Go1 (``env.randomize.preset=field``), each with its
    # source: MuJoCo Playground's Go1 joystick domain randomisation (floor friction U(0.4, 1.0),
    # armature x U(1.0, 1.05), torso mass + U(-1, 1) kg: its non-negative half, a payload
    # here); walk-these-ways' Go1 (Margolis & Agrawal 2022, go1_gym: motor strength
    # 0.9-1.1, Kp factor 0.8-1.3, Kd factor 0.5-1.5, actions late by up to 6 steps of 5 ms:
    # 0-1.5 control steps here); legged_gym's sensor noise at level 1 and pushes up to 1 m/s
    # (every 5-10 s: QuadrupedConfig's). Passive damping 0-1.5 x and the contact's time
    # constant 0.5-2 x are this project's choice (no recipe for the Go1 randomises them): the
    # damping range reaches mjlab's Go1, which has none (robots/go1/variant.py).
    FIELD_RANDOMIZATION = {
        "friction": (0.4, 1.0),
        "payload": (0.0, 1.0),
        "armature": (1.0, 1.05),
        "motor_strength": (0.9, 1.1),
        "kp_scale": (0.8, 1.3),
        "kd_scale": (0.5, 1.5),
        "latency": (0.0, 1.5),
        "obs_noise": (1.0, 1.0),
        "joint_damping": (0.0, 1.5),
        "contact_softness": (0.5, 2.0),
        "push_velocity": (0.0, 1.0),
        "push_interval": (5.0, 10.0),
    }
    body = "unitree-go1"
    # MuJoCo Playground's Go1 joystick recipe, its env values (--preset playground;
    # robots/go1/playground.py gives each its source and the departures)
    PLAYGROUND = PLAYGROUND
    LEGGED_GYM = None  # legged_gym's recipe here is ANYmal B's (QuadrupedConfig's)
