"""`QuadrupedConfig`: every number of a quadruped's locomotion task, with its reason.

Its defaults are ANYmal B's (the first quadruped here); another robot subclasses it and changes
the defaults where its body differs (``robots/go1/config.py``). The actuator constants are one
number for all 12 joints, or three, one per joint of a leg (in the leg's joint order), repeated
for each leg.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

from cpg_actor.limits import (
    MAX_EPISODE_STEPS,
    brief,
    shorten,
)
from cpg_actor.robots.common.checks import check_episode_steps, check_simulation_counts
from cpg_actor.robots.common.perturbation import Perturbation, Randomization, check_perturbations
from cpg_actor.robots.common.perturbation.values import RANDOMIZED, TRAINING_PUSHES
from cpg_actor.robots.common.quadruped.legged_gym import LEGGED_GYM
from cpg_actor.tasks.velocity import NOISE_GROUPS, TERMS
from cpg_actor.terrain.config import Terrain, check_terrain


def default_scales() -> dict[str, float]:
    # legged_gym's ANYmal scales (Rudin et al. 2021), per second of simulated time (each term is
    # multiplied by the control step), plus the two terms the task asks for that legged_gym
    # leaves at 0: orientation and base height.
    return {
        "tracking_lin_vel": 1.0,  # exp(-|v_xy - command_xy|^2 / sigma)
        "tracking_ang_vel": 0.5,  # exp(-(w_z - command_yaw)^2 / sigma)
        "lin_vel_z": -2.0,  # v_z^2: no bouncing
        "ang_vel_xy": -0.05,  # w_x^2 + w_y^2: no rocking
        "orientation": -1.0,  # |projected gravity xy|^2: keep the base level
        "base_height": -10.0,  # (h - base_height_target)^2
        "torques": -1e-5,  # |tau|^2
        "joint_acc": -2.5e-7,  # |q_ddot|^2
        "action_rate": -0.01,  # |a_t - a_t-1|^2
        "feet_air_time": 1.0,  # sum over touchdowns of (air time - 0.5 s): longer steps
        # sum over planted feet of their sliding speed^2 (m/s)^2. Off (0) by default, as in
        # legged_gym; the trained MLP drags its hind feet without it (docs/quadruped.md)
        "feet_slip": 0.0,
    }


SIMULATORS = ("mujoco", "mjx")  # the quadruped's backends
PUSH_DIRECTIONS = ("forward", "backward", "left", "right")  # in the base's heading frame
ACTUATOR_FIELDS = ("kp", "kd", "torque_limit", "velocity_limit", "saturation_torque")


def _number(value, bound: float, strict: bool) -> bool:
    """A finite int or float (no bool) above ``bound`` (``strict``) or at least it."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        return False
    return value > bound if strict else value >= bound


# MJX's implementations: its own in JAX, or MuJoCo Warp's kernels called from JAX
MJX_IMPLEMENTATIONS = ("jax", "warp")
FLOOR_CONTACTS = ("auto", "all", "feet")  # QuadrupedConfig.floor_contacts


@dataclass
class QuadrupedConfig:
    """The locomotion task of a quadruped; the defaults are ANYmal B's (``docs/quadruped.md``)."""

    # "mujoco" (MuJoCo on the CPU, the default) or "mjx" (MuJoCo XLA: JAX on a GPU where it
    # has one; docs/quadruped.md, "Backends")
    sim: str = "mujoco"
    # sim="mjx" only: the Newton solver's iteration caps (the MJX hopper's; HopperConfig). The
    # trot needs more than 4 iterations to stay on MuJoCo's trajectory (docs/gpu.md)
    mjx_iterations: int = 15
    mjx_ls_iterations: int = 15
    # sim="mjx" only: MJX's implementation, "jax" (MJX's own, any JAX device) or "warp"
    # (MuJoCo Warp's kernels inside JAX: needs the warp-lang package; docs/gpu.md)
    mjx_impl: str = "jax"
    # which of the robot's geoms touch the floor: "all" (every collision geom: the trunk,
    # thighs and calves too), "feet" (the feet alone, as MuJoCo Playground's feet-only MJX
    # scenes), or "auto": the feet alone on MJX, where every potential contact costs solver
    # rows whether it touches or not (the Go1's 31 geoms: 5x the rows), all on MuJoCo, whose
    # collision stage skips geoms far from the floor. A fall ends an episode before anything
    # but a foot rests on flat ground (docs/quadruped.md, "Backends")
    floor_contacts: str = "auto"
    physics_dt: float = 0.002  # s: 500 Hz, stable for this robot's contacts (legged_gym: 5 ms)
    decimation: int = 10  # substeps per control step: control at 50 Hz (legged_gym's)
    episode_seconds: float = 20.0  # s, then truncated
    foot_friction: float = 0.8  # the hopper's
    # the hopper's actuator law on all 12 joints (cpg_actor.robots.common.actuator); each a
    # number, or three: one per joint of a leg
    kp: float | tuple[float, ...] = 80.0  # N m / rad
    kd: float | tuple[float, ...] = 2.0  # N m s / rad
    torque_limit: float | tuple[float, ...] = 40.0  # N m
    velocity_limit: float | tuple[float, ...] = 15.0  # rad/s
    saturation_torque: float | tuple[float, ...] = 80.0  # N m
    actuator_law: str = "dc-motor"
    # commands, each uniform in its range: forward and lateral speed (base frame) and yaw
    # rate. Lateral and yaw are 0 by default (the forward task); the omnidirectional task
    # (the "omni" recipe, OMNI_COMMANDS) takes the field's ranges
    command_range: tuple[float, float] = (0.0, 1.0)  # m/s
    lateral_range: tuple[float, float] = (0.0, 0.0)  # m/s, positive to the left
    yaw_range: tuple[float, float] = (0.0, 0.0)  # rad/s, positive counter-clockwise
    # s between draws of a new command within an episode (legged_gym's 10 s, Playground's
    # 5 s); 0 or None: one command per episode (the forward task's)
    command_resample_seconds: float | None = 0.0
    # the share of draws (at an episode's start and at each resampling) whose command is
    # zero: standing still
    standing_share: float = 0.0
    # (m/s)^2 and (rad/s)^2 of the tracking kernels. legged_gym's 0.25 pays 96% of the term at
    # 0.1 m/s of error, too little pull to track a command within 0.1 m/s; 0.1 pays 90% there
    # (docs/quadruped.md)
    tracking_sigma: float = 0.1
    base_height_target: float = 0.48  # m: where the nominal pose stands under its weight
    reward_scales: dict[str, float] = field(default_factory=default_scales)
    reset_noise: float = 0.1  # rad, uniform on each joint around the nominal pose
    fall_height: float = 0.25  # m: a base lower than this has fallen (standing: 0.48)
    fall_tilt: float = 1.0  # rad: a base tilted more than this has fallen
    normalized_actions: bool = False  # actions in [-1, 1] mapped onto the joint ranges
    render_width: int = 640  # pixels of render_frame's images (videos)
    render_height: int = 480
    # perturbations (the robustness suite's; docs/robustness.md): none by default
    perturbation: Perturbation = field(default_factory=Perturbation)
    randomize: Randomization = field(default_factory=Randomization)  # randomised training
    # rough ground (cpg_actor.terrain; docs/quadruped.md, "Terrain"): flat by default
    terrain: Terrain = field(default_factory=Terrain)
    # -- options of other recipes (MuJoCo Playground's: the playground preset, docs/go1.md);
    # each off by default, each MuJoCo's only (not the MJX env's) --------------------------
    # the reward of a step clipped below at this (Playground: 0, legged_gym's
    # only_positive_rewards: ending an episode never pays); None: not clipped
    reward_clip_min: float | None = None
    # the actions are nominal + action_scale x a with a in [-1, 1] (Playground: 0.5): the
    # action space is the nominal pose +- action_scale rad (within the action limits) and the
    # action rate is measured in a's units; 0: the robot's action limits, the rate in rad
    action_scale: float = 0.0
    observe_lin_vel: bool = False  # the base's linear velocity (base frame) in the observation
    # the critic's privileged entries after the actor's (task.privileged_names): an agent with
    # agent_config.privileged_critic feeds them to its critic alone
    privileged_observation: bool = False
    # uniform noise x + U(-w, w) on the actor's observation at every step, w per group
    # (task.NOISE_GROUPS: gyro, gravity, joint_pos, joint_vel, lin_vel); empty: none
    observation_noise: dict[str, float] = field(default_factory=dict)
    # the field terms' numbers (task.field_terms): the pose term's weight on each joint of a
    # leg (abduction, hip, knee), the feet_height term's target swing height (m), the
    # feet_air_time_commanded term's air time (s) and the soft joint limits of
    # dof_pos_limits (this fraction of each joint's range bounds, as Playground scales them)
    leg_pose_weights: tuple[float, float, float] = (1.0, 1.0, 0.1)
    max_foot_height: float = 0.1
    air_time_target: float = 0.1
    soft_joint_limit_factor: float = 0.95
    # Playground's command process: at a resampling each of (vx, vy, yaw) is kept with
    # probability command_hold, else drawn again uniform in its range and kept nonzero with
    # its probability in command_nonzero (None: the standing_share rule, no hold); with
    # command_interval "exponential" the time to the next resampling is exponential with
    # mean command_resample_seconds ("fixed": every command_resample_seconds)
    command_nonzero: tuple[float, float, float] | None = None
    command_hold: float = 0.0
    command_interval: str = "fixed"
    # -- legged_gym's (the legged_gym preset, docs/quadruped.md); each off by default, each
    # MuJoCo's only ------------------------------------------------------------------------
    # its heading command (> 0): at each draw a heading uniform in heading_range (rad, the
    # world's yaw) is drawn instead of the yaw rate, and after every step the yaw-rate command
    # is heading_gain x (heading - the base's yaw, wrapped to +-pi) clipped to yaw_range
    heading_gain: float = 0.0
    heading_range: tuple[float, float] = (-math.pi, math.pi)
    # a drawn (vx, vy) of norm at most this (m/s) is zeroed: standing still (legged_gym: 0.2)
    min_command_speed: float = 0.0
    # the start: each joint at its nominal angle times U(low, high) (legged_gym: (0.5, 1.5);
    # None: not scaled), then the reset_noise; each of the base's six velocities (linear m/s,
    # angular rad/s) uniform in +-reset_base_velocity (0: at rest)
    reset_joint_scale: tuple[float, float] | None = None
    reset_base_velocity: float = 0.0

    @property
    def control_dt(self) -> float:
        return self.physics_dt * self.decimation

    @property
    def feet_only(self) -> bool:
        """Whether the feet alone touch the floor (``floor_contacts``)."""
        return self.floor_contacts == "feet" or (
            self.floor_contacts == "auto" and self.sim == "mjx"
        )

    @property
    def episode_steps(self) -> int:
        return round(self.episode_seconds / self.control_dt)

    @property
    def resample_steps(self) -> int:
        """Control steps between command draws within an episode; 0: one per episode."""
        if not self.command_resample_seconds:
            return 0
        return max(1, round(self.command_resample_seconds / self.control_dt))

    # The omnidirectional task's values (the "omni" recipe, cpg_actor.config.presets): the
    # field's command ranges (legged_gym, mjlab, MuJoCo Playground), a command held 5 s, one
    # draw in ten standing still. A robot whose body needs other ranges gives its own.
    OMNI_COMMANDS: ClassVar[dict[str, Any]] = {
        "command_range": (-1.0, 1.0),
        "lateral_range": (-0.5, 0.5),
        "yaw_range": (-1.0, 1.0),
        "command_resample_seconds": 5.0,
        "standing_share": 0.1,
    }

    def validate(self) -> QuadrupedConfig:
        """Raise ``ValueError`` naming the first bad field; returns ``self``."""
        for name in ("physics_dt", "episode_seconds", "tracking_sigma", "base_height_target",
                     "fall_height", "fall_tilt"):  # fmt: skip
            value = getattr(self, name)
            if not _number(value, 0.0, strict=True):
                raise ValueError(f"{name} must be a positive finite number, got {brief(value)}")
        for name in ("foot_friction", "reset_noise"):
            value = getattr(self, name)
            if not _number(value, 0.0, strict=False):
                raise ValueError(f"{name} must be a finite number >= 0, got {brief(value)}")
        for name in ACTUATOR_FIELDS:
            value, strict = getattr(self, name), name != "kd"
            if isinstance(value, list):  # from YAML or --set
                value = tuple(value)
                setattr(self, name, value)
            ok = _number(value, 0.0, strict) or (
                isinstance(value, tuple) and len(value) == 3
                and all(_number(v, 0.0, strict) for v in value)
            )  # fmt: skip
            if not ok:
                raise ValueError(f"{name} must be a finite number {'>' if strict else '>='} 0 "
                                 f"or three of them (one per joint of a leg), got "
                                 f"{brief(value)}")  # fmt: skip
        if self.sim not in SIMULATORS:
            raise ValueError(f"sim must be one of {', '.join(SIMULATORS)} for the quadruped, "
                             f"got {brief(self.sim)}")  # fmt: skip
        if self.mjx_impl not in MJX_IMPLEMENTATIONS:
            raise ValueError(f"mjx_impl must be one of {', '.join(MJX_IMPLEMENTATIONS)}, got "
                             f"{brief(self.mjx_impl)}")  # fmt: skip
        if self.floor_contacts not in FLOOR_CONTACTS:
            raise ValueError(f"floor_contacts must be one of {', '.join(FLOOR_CONTACTS)}, got "
                             f"{brief(self.floor_contacts)}")  # fmt: skip
        check_simulation_counts(self)
        if self.physics_dt > 0.005:
            raise ValueError(f"physics_dt must be <= 0.005 s, got {self.physics_dt}")
        # as a float: a tiny physics_dt makes it too large to round to an integer
        check_episode_steps(self.episode_seconds / self.control_dt,
                            f"episode_seconds={self.episode_seconds:g}")  # fmt: skip
        for name, unit in (("command_range", "m/s"), ("lateral_range", "m/s"),
                           ("yaw_range", "rad/s")):  # fmt: skip
            bounds = getattr(self, name)
            if not (
                isinstance(bounds, list | tuple)
                and len(bounds) == 2
                and all(isinstance(b, int | float) and math.isfinite(b) for b in bounds)
                and bounds[0] <= bounds[1]
            ):
                raise ValueError(f"{name} must be [low, high] in {unit} with low <= high, got "
                                 f"{brief(bounds)}")  # fmt: skip
            setattr(self, name, tuple(bounds))  # a list from YAML or --set, as the defaults
        period = self.command_resample_seconds
        if period is not None and not (
            _number(period, 0.0, strict=False) and period / self.control_dt <= MAX_EPISODE_STEPS
        ):
            raise ValueError(f"command_resample_seconds must be a number of seconds >= 0, at "
                             f"most {MAX_EPISODE_STEPS:,} control steps (0 or None: one command "
                             f"per episode), got {brief(period)}")  # fmt: skip
        share = self.standing_share
        if not (_number(share, 0.0, strict=False) and share <= 1.0):
            raise ValueError(f"standing_share must be a number in [0, 1] (the share of zero "
                             f"commands), got {brief(share)}")  # fmt: skip
        if not isinstance(self.reward_scales, dict):
            raise ValueError(f"reward_scales must be a mapping of term to scale, got "
                             f"{brief(self.reward_scales)}")  # fmt: skip
        unknown = set(self.reward_scales) - set(TERMS)
        if unknown:
            raise ValueError(
                f"unknown reward terms {brief(sorted(map(str, unknown)))}; accepted: "
                f"{sorted(TERMS)}"
            )
        for term, scale in self.reward_scales.items():
            if isinstance(scale, bool) or not (isinstance(scale, int | float)
                                               and math.isfinite(scale)):  # fmt: skip
                raise ValueError(
                    f"reward_scales.{shorten(term)} must be a finite number, got {brief(scale)}"
                )
        if self.actuator_law not in ("dc-motor", "coast"):
            raise ValueError(f"actuator_law must be 'dc-motor' or 'coast', got "
                             f"{brief(self.actuator_law)}")  # fmt: skip
        check_perturbations(
            self,
            PUSH_DIRECTIONS,
            ("mujoco",),  # not on MJX
            supported=(*RANDOMIZED, *TRAINING_PUSHES),
            robot=self.body,
        )
        check_terrain(self)
        check_recipe_options(self)
        return self

    # the mass the robot moves, kg (ANYmal B's: robots/anymal/description.py TOTAL_MASS), which
    # sizes its payloads and pushes
    moving_mass = 30.4214
    # randomised training's ranges for this robot (``env.randomize.preset=field``), each from
    # legged_gym's ANYmal recipe (Rudin et al. 2021, anymal_c_rough_config.py, which ANYmal B's
    # inherits): ground friction 0.5-1.25; added base mass +-5 kg, its non-negative half (a
    # payload here); sensor noise at its level 1 in every episode; pushes up to 1 m/s (legged_gym:
    # each horizontal component up to 1 m/s every 15 s; here a kick of up to 1 m/s in a random
    # direction every 5-10 s, a few per 20 s episode). legged_gym randomises nothing else on
    # ANYmal: the drives, joints and contact stay nominal.
    FIELD_RANDOMIZATION = {
        "friction": (0.5, 1.25),
        "payload": (0.0, 5.0),
        "obs_noise": (1.0, 1.0),
        "push_velocity": (0.0, 1.0),
        "push_interval": (5.0, 10.0),
    }
    # the body these numbers are for (its QuadrupedModel's name): a subclass for another body
    # names its own, one that changes only numbers (a variant of the robot) keeps it
    body = "anymal-b"
    # legged_gym's ANYmal B recipe, its env values (--preset legged_gym; legged_gym.py beside
    # this file gives each its source and the departures); a body without it sets None
    LEGGED_GYM: ClassVar[dict[str, Any] | None] = LEGGED_GYM

    @classmethod
    def perturbation_table(cls):
        """The perturbations the robustness suite runs on this quadruped."""
        from cpg_actor.robots.common.quadruped.perturbations import perturbation_table

        return perturbation_table(cls.moving_mass, cls().foot_friction)

    def replace(self, **changes) -> QuadrupedConfig:
        """A validated copy with ``changes`` (as the hopper's ``HopperConfig.replace``)."""
        return dataclasses.replace(self, **changes).validate()

    @classmethod
    def from_dict(cls, values: dict) -> QuadrupedConfig:
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = set(values) - names
        if unknown:
            raise ValueError(
                f"unknown {cls.__name__} fields {brief(sorted(map(str, unknown)))}; accepted: "
                f"{sorted(names)}"
            )
        given = values.get("reward_scales", {})
        if not isinstance(given, dict):
            raise ValueError(
                f"reward_scales must be a mapping of term to scale, got {brief(given)}"
            )
        scales = {**cls().reward_scales, **given}  # the class's defaults for the others
        return cls(**{**values, "reward_scales": scales}).validate()


RECIPE_OPTIONS = ("reward_clip_min", "action_scale", "observe_lin_vel", "privileged_observation",
                  "observation_noise", "command_nonzero", "command_hold", "command_interval",
                  "heading_gain", "min_command_speed", "reset_joint_scale",
                  "reset_base_velocity")  # fmt: skip
COMMAND_INTERVALS = ("fixed", "exponential")


def check_recipe_options(config: QuadrupedConfig) -> None:
    """ValueError naming the first bad option of another recipe (``QuadrupedConfig``'s
    "options of other recipes"); they are MuJoCo's only."""
    clip = config.reward_clip_min
    if clip is not None and (isinstance(clip, bool) or not _number(clip, -math.inf, True)):
        raise ValueError(f"reward_clip_min must be a finite number or null, got {brief(clip)}")
    if not _number(config.action_scale, 0.0, strict=False):
        raise ValueError(f"action_scale must be a finite number >= 0 (rad; 0: the action "
                         f"limits), got {brief(config.action_scale)}")  # fmt: skip
    for name in ("observe_lin_vel", "privileged_observation"):
        if not isinstance(getattr(config, name), bool):
            raise ValueError(f"{name} must be true or false, got {brief(getattr(config, name))}")
    noise = config.observation_noise
    if (
        not isinstance(noise, dict)
        or set(noise) - set(NOISE_GROUPS)
        or not all(_number(w, 0.0, strict=False) for w in noise.values())
    ):
        raise ValueError(f"observation_noise must map some of {', '.join(NOISE_GROUPS)} to "
                         f"half-widths >= 0, got {brief(noise)}")  # fmt: skip
    if isinstance(config.leg_pose_weights, list):
        config.leg_pose_weights = tuple(config.leg_pose_weights)
    weights = config.leg_pose_weights
    if not (isinstance(weights, tuple) and len(weights) == 3
            and all(_number(w, 0.0, strict=False) for w in weights)):  # fmt: skip
        raise ValueError(f"leg_pose_weights must be three numbers >= 0 (abduction, hip, knee), "
                         f"got {brief(weights)}")  # fmt: skip
    for name in ("max_foot_height", "air_time_target"):
        if not _number(getattr(config, name), 0.0, strict=True):
            raise ValueError(f"{name} must be a positive finite number, got "
                             f"{brief(getattr(config, name))}")  # fmt: skip
    factor = config.soft_joint_limit_factor
    if not (_number(factor, 0.0, strict=True) and factor <= 1.0):
        raise ValueError(f"soft_joint_limit_factor must be in (0, 1], got {brief(factor)}")
    if isinstance(config.command_nonzero, list):
        config.command_nonzero = tuple(config.command_nonzero)
    nonzero = config.command_nonzero
    if nonzero is not None and not (isinstance(nonzero, tuple) and len(nonzero) == 3 and all(
            _number(b, 0.0, strict=False) and b <= 1.0 for b in nonzero)):  # fmt: skip
        raise ValueError(f"command_nonzero must be three probabilities (vx, vy, yaw) or null, "
                         f"got {brief(nonzero)}")  # fmt: skip
    hold = config.command_hold
    if not (_number(hold, 0.0, strict=False) and hold <= 1.0):
        raise ValueError(f"command_hold must be a probability in [0, 1], got {brief(hold)}")
    if config.command_interval not in COMMAND_INTERVALS:
        raise ValueError(f"command_interval must be one of {', '.join(COMMAND_INTERVALS)}, got "
                         f"{brief(config.command_interval)}")  # fmt: skip
    if config.command_interval == "exponential" and not config.command_resample_seconds:
        raise ValueError(
            "command_interval 'exponential' needs command_resample_seconds > 0 "
            "(the mean time between resamplings)"
        )
    check_legged_gym_options(config)
    if config.sim == "mjx":
        nominal = type(config)()
        given = [name for name in RECIPE_OPTIONS
                 if getattr(config, name) != getattr(nominal, name)]  # fmt: skip
        if given:
            raise ValueError(f"{', '.join(given)}: MuJoCo's only; the MJX env does not "
                             f"implement them (use sim='mujoco')")  # fmt: skip


def check_legged_gym_options(config: QuadrupedConfig) -> None:
    """ValueError naming the first bad option of legged_gym's recipe (``heading_gain``,
    ``heading_range``, ``min_command_speed``, ``reset_joint_scale``,
    ``reset_base_velocity``)."""
    for name in ("heading_gain", "min_command_speed", "reset_base_velocity"):
        if not _number(getattr(config, name), 0.0, strict=False):
            raise ValueError(f"{name} must be a finite number >= 0, got "
                             f"{brief(getattr(config, name))}")  # fmt: skip
    for name in ("heading_range", "reset_joint_scale"):
        bounds = getattr(config, name)
        if bounds is None and name == "reset_joint_scale":
            continue
        low = -math.inf if name == "heading_range" else 0.0
        if not (isinstance(bounds, list | tuple) and len(bounds) == 2
                and all(_number(b, low, strict=False) for b in bounds)
                and bounds[0] <= bounds[1]):  # fmt: skip
            what = "rad" if name == "heading_range" else "factors >= 0"
            raise ValueError(f"{name} must be [low, high] ({what}) with low <= high"
                             f"{' or null' if name == 'reset_joint_scale' else ''}, got "
                             f"{brief(bounds)}")  # fmt: skip
        setattr(config, name, (float(bounds[0]), float(bounds[1])))
