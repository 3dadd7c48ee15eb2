"""`HopperConfig`: every number of the hopper environment, with its documented default.

See ``docs/hopper.md`` for why each default is what it is.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

from cpg_actor.limits import (
    brief,
    shorten,
)
from cpg_actor.robots.common.checks import check_episode_steps, check_simulation_counts
from cpg_actor.robots.common.perturbation import Perturbation, Randomization, check_perturbations
from cpg_actor.robots.hopper.backends import BACKENDS, BATCHED_ONLY

SIMULATORS = (*BACKENDS, BATCHED_ONLY)  # the backends' and MJX
ACTUATOR_LAWS = ("dc-motor", "coast")  # see cpg_actor.robots.common.actuator
HOP_REWARDS = ("hip-velocity", "apex")  # see cpg_actor.robots.hopper.reward
PUSH_DIRECTIONS = ("up", "down")  # along the rail


@dataclass
class HopperConfig:
    """The single-leg ANYmal hopper (paper section IV): simulation, actuator, reward, episode."""

    # -- simulation ------------------------------------------------------------------------
    # "mujoco" (fast default), "pybullet" (the paper's simulator) or "mjx" (MuJoCo XLA: JAX on a
    # GPU; batched only, docs/gpu.md)
    sim: str = "mujoco"
    physics_dt: float = 0.001  # s, physics substep (1 kHz)
    decimation: int = 10  # physics substeps per control step: control at 100 Hz
    episode_steps: int = 500  # control steps per episode: 5 s, then truncated
    foot_friction: float = 0.8  # Coulomb friction between foot and ground
    # sim="mjx" only: the constraint solver's iteration caps. MJX solves the batch together until
    # its slowest robot converges, and runs every line-search iteration batched, so these caps
    # set its cost; MuJoCo's defaults are 100 and 50. 15 and 15 are the lowest caps that give
    # the same trajectories and returns as 100 and 50 for the hopper and the quadruped's trot
    # (docs/gpu.md)
    mjx_iterations: int = 15
    mjx_ls_iterations: int = 15
    # -- actuator (PD on the desired position, torque-speed limited; see actuator.py) ---------
    kp: float = 80.0  # N m / rad
    kd: float = 2.0  # N m s / rad
    torque_limit: float = 40.0  # N m, |tau| <= torque_limit
    velocity_limit: float = 15.0  # rad/s, no-load speed: only braking torque beyond it
    saturation_torque: float = 80.0  # N m, stall torque: line tau_sat (1 - v / v_max)
    # beyond v_max: "dc-motor" brakes (back-EMF; run inside MuJoCo), "coast" gives no torque in
    # the direction of motion (numpy at every substep, outside MuJoCo's own loop)
    actuator_law: str = "dc-motor"
    # -- reward, paper eq. 4 (c1 >= 0, c2..c5 <= 0) --------------------------------------------
    c1: float = 1.0  # r1 = (c1 * max(v_hip, 0))^2: upward hip velocity, (m/s)^2
    c2: float = -1.0  # r2 = c2 * sum_j (p_d - p_m)^2: tracking error, rad^2
    c3: float = -1e-3  # r3 = c3 * sum_j v_m^2: joint velocity, (rad/s)^2
    c4: float = -1e-4  # r4 = c4 * sum_j tau_d^2: joint torque, (N m)^2
    c5: float = -0.1  # r5 = c5 * |v_foot_xy|: foot slip, m/s
    # r1 (beyond the paper): "hip-velocity" is eq. 4's (c1 max(v_hip, 0))^2 at every step;
    # "apex" pays apex_weight x the centre of mass's apex above the highest standing centre of
    # mass, once per flight: the hop height itself, nothing for pushing up in stance
    hop_reward: str = "hip-velocity"
    apex_weight: float = 200.0  # reward per m of apex height ("apex" only)
    # -- reset --------------------------------------------------------------------------------
    reset_noise: float = 0.1  # rad, uniform noise on each joint around the nominal pose
    reset_clearance: float = 0.0  # m, foot height above the ground at reset
    # -- termination: a simulation blow-up ends the episode (terminated) ------------------------
    blowup_joint_velocity: float = 200.0  # rad/s
    blowup_hip_velocity: float = 50.0  # m/s
    # -- interface ----------------------------------------------------------------------------
    # actions in [-1, 1] per joint, mapped linearly to the joint's range (the desired
    # position, rad), for off-the-shelf RL libraries; the project's agents act in radians
    normalized_actions: bool = False
    # a first-order low-pass on the command: the desired positions move by this share of the
    # way from the last ones to the agent's command each control step (task.command_filter);
    # 1.0 is no filter. For an agent made as smooth as a CPG by its env (matched smoothness)
    command_filter: float = 1.0
    # -- rendering ----------------------------------------------------------------------------
    render_width: int = 640
    render_height: int = 480
    # -- perturbations (the robustness suite's; docs/robustness.md): none by default -----------
    perturbation: Perturbation = field(default_factory=Perturbation)
    randomize: Randomization = field(default_factory=Randomization)  # randomised training

    def __post_init__(self) -> None:
        self.validate()

    @property
    def control_dt(self) -> float:
        """Seconds per control step: ``physics_dt * decimation``."""
        return self.physics_dt * self.decimation

    @property
    def reward_weights(self) -> tuple[float, float, float, float, float]:
        return (self.c1, self.c2, self.c3, self.c4, self.c5)

    def validate(self) -> None:
        """Raise ValueError naming the first invalid field."""
        alpha = self.command_filter
        if isinstance(alpha, bool) or not isinstance(alpha, (int, float)) or not 0 < alpha <= 1:
            raise ValueError(
                f"command_filter must be a number in (0, 1] (1.0: no filter), got {brief(alpha)}"
            )
        for name, kind in _FIELD_KINDS.items():
            value = getattr(self, name)
            if kind is str:
                if not isinstance(value, str):
                    raise ValueError(f"{name} must be a string, got {brief(value)}")
            elif kind is bool:
                if not isinstance(value, bool):
                    raise ValueError(f"{name} must be true or false, got {brief(value)}")
            elif kind is int:
                if isinstance(value, bool) or not isinstance(value, int):
                    raise ValueError(f"{name} must be an integer, got {brief(value)}")
            else:
                if isinstance(value, bool) or not isinstance(value, (int, float)):
                    raise ValueError(f"{name} must be a number, got {brief(value)}")
                if not math.isfinite(value):
                    raise ValueError(f"{name} must be finite, got {brief(value)}")
        if self.sim not in SIMULATORS:
            raise ValueError(f"sim must be one of {', '.join(SIMULATORS)}, got {brief(self.sim)}")
        if self.actuator_law not in ACTUATOR_LAWS:
            raise ValueError(
                f"actuator_law must be one of {', '.join(ACTUATOR_LAWS)}, "
                f"got {brief(self.actuator_law)}"
            )
        positive = (
            "physics_dt decimation episode_steps kp torque_limit velocity_limit "
            "saturation_torque blowup_joint_velocity blowup_hip_velocity "
            "mjx_iterations mjx_ls_iterations "
            "render_width render_height"
        ).split()
        for name in positive:
            if getattr(self, name) <= 0:
                raise ValueError(f"{name} must be > 0, got {brief(getattr(self, name))}")
        check_simulation_counts(self)
        for name in ("kd", "foot_friction", "reset_noise", "reset_clearance"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0, got {brief(getattr(self, name))}")
        if self.physics_dt > 0.005:
            raise ValueError(
                f"physics_dt must be <= 0.005 s for stable contacts, got {self.physics_dt}"
            )
        check_episode_steps(self.episode_steps, f"episode_steps={self.episode_steps}")
        if self.saturation_torque < self.torque_limit:
            raise ValueError(
                f"saturation_torque ({self.saturation_torque}) must be >= torque_limit "
                f"({self.torque_limit})"
            )
        if self.hop_reward not in HOP_REWARDS:
            raise ValueError(
                f"hop_reward must be one of {HOP_REWARDS}, got {brief(self.hop_reward)}"
            )
        if not self.apex_weight >= 0:
            raise ValueError(f"apex_weight must be >= 0, got {brief(self.apex_weight)}")
        if self.c1 < 0:
            raise ValueError(f"c1 must be >= 0 (paper eq. 4: r1 rewards hopping), got {self.c1}")
        for name in ("c2", "c3", "c4", "c5"):
            if getattr(self, name) > 0:
                raise ValueError(
                    f"{name} must be <= 0 (paper eq. 4: r2..r5 are penalties), "
                    f"got {getattr(self, name)}"
                )
        # last: the push's window is checked against the episode's length
        check_perturbations(
            self,
            PUSH_DIRECTIONS,
            tuple(BACKENDS),  # not on MJX
            robot="the hopper",
        )

    # randomised training's ranges for the hopper (``env.randomize.preset=field``): those of the
    # reproduction's randomised variants (docs/robustness.md), within the suite's levels;
    # legged_gym randomises friction 0.5-1.25 and the base's mass by +-1 kg and adds its sensor
    # noise at level 1
    FIELD_RANDOMIZATION = {
        "payload": (0.0, 1.02),
        "friction": (0.4, 1.2),
        "latency": (0.0, 1.0),
        "obs_noise": (0.0, 1.0),
        "motor_strength": (0.8, 1.2),
    }

    # -- (de)serialisation -------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> HopperConfig:
        """Build from a mapping; unknown keys are a ValueError listing them and the valid ones."""
        if not isinstance(data, dict):
            raise ValueError(f"HopperConfig.from_dict expects a mapping, got {type(data).__name__}")
        accepted = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(str(k) for k in data if k not in accepted)
        if unknown:
            raise ValueError(
                f"unknown HopperConfig key(s): {shorten(', '.join(unknown))}; "
                f"accepted keys: {', '.join(accepted)}"
            )
        values = {}
        for key, value in data.items():
            # YAML writes 100.0 as 100: accept integers for float fields (bools stay invalid)
            if (
                _FIELD_KINDS.get(key) is float
                and isinstance(value, int)
                and not isinstance(value, bool)
            ):
                value = float(value)
            values[key] = value
        return cls(**values)

    def replace(self, **changes: Any) -> HopperConfig:
        """A copy with some fields changed (validated; unknown keys are a ValueError)."""
        return HopperConfig.from_dict({**self.to_dict(), **changes})

    @classmethod
    def perturbation_table(cls):
        """The perturbations the robustness suite runs on the hopper."""
        from cpg_actor.robots.hopper.perturbations import perturbation_table

        return perturbation_table()


# the plain fields' kinds (the perturbation and the randomisation are sections of their own)
_FIELD_KINDS = {
    f.name: {"str": str, "int": int, "float": float, "bool": bool}[f.type]
    for f in dataclasses.fields(HopperConfig)
    if f.name not in ("perturbation", "randomize")
}
