"""What a perturbation is (:class:`Perturbation`, ``env.perturbation``) and randomised
training's ranges (:class:`Randomization`, ``env.randomize``), with their validation."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from cpg_actor.limits import brief
from cpg_actor.robots.common.checks import mapping_fields

# the push's direction: along the hopper's rail, or in the quadruped base's heading frame
PUSH_DIRECTIONS = {
    "up": (0.0, 0.0, 1.0),
    "down": (0.0, 0.0, -1.0),
    "forward": (1.0, 0.0, 0.0),
    "backward": (-1.0, 0.0, 0.0),
    "left": (0.0, 1.0, 0.0),
    "right": (0.0, -1.0, 0.0),
}


# the largest value of each: far beyond the suite's levels (docs/robustness.md), small enough
# that the simulation stays meaningful and the latency's command buffer small
HIGHS = {"payload": 100.0, "friction": 10.0, "latency": 50.0, "obs_noise": 100.0,
         "motor_strength": 10.0, "push": 100.0, "kp_scale": 10.0, "kd_scale": 10.0,
         "joint_damping": 100.0, "armature": 100.0, "contact_softness": 10.0,
         "push_velocity": 10.0, "push_interval": 1000.0}  # fmt: skip
# the model terms only the quadrupeds take (their MuJoCo model is rebuilt per episode):
# factors on the drive's PD gains, the joints' passive damping and armature, and the contact
# time constant (solref) of the feet and the ground
MODEL_TERMS = ("kp_scale", "kd_scale", "joint_damping", "armature", "contact_softness")


@dataclass
class Perturbation:
    """What is done to the robot and its world; the defaults are the nominal robot."""

    payload: float = 0.0  # kg added to the hip (hopper) or the base (quadrupeds), at its COM
    friction: float | None = None  # foot-ground sliding friction; None: the env's foot_friction
    # control steps between the policy's command and the drives tracking it; a fraction delays
    # by whole physics substeps within a step (latency x decimation must be an integer)
    latency: float = 0.0
    # sensor noise, in multiples of the robot's sensor noise (its task's SENSOR_NOISE: std per
    # observation entry, 0 for what is not a sensor's); Gaussian, drawn at every observation
    obs_noise: float = 0.0
    motor_strength: float = 1.0  # x the PD gains, the torque limit and the stall torque
    push: float = 0.0  # N s: an impulse on the hip or base, spread over one control step
    push_direction: str = "up"  # a key of PUSH_DIRECTIONS the robot accepts (with a push)
    # s: the push comes at a control step drawn uniformly in this window of each episode
    push_time: tuple[float, float] = (1.0, 2.0)
    # the quadrupeds' model terms (MODEL_TERMS), factors on the robot's own values
    kp_scale: float = 1.0  # x the drives' stiffness Kp (with the motor strength's)
    kd_scale: float = 1.0  # x the drives' damping Kd (with the motor strength's)
    joint_damping: float = 1.0  # x the joints' passive damping
    armature: float = 1.0  # x the joints' armature (reflected rotor inertia)
    contact_softness: float = 1.0  # x the feet's and the ground's contact time constant

    @property
    def nominal(self) -> bool:
        """Whether it changes nothing (the push's direction and time then do not matter)."""
        return (self.payload == 0.0 and self.friction is None and self.latency == 0.0
                and self.obs_noise == 0.0 and self.motor_strength == 1.0
                and self.push == 0.0 and self.model_nominal)  # fmt: skip

    @property
    def model_nominal(self) -> bool:
        """Whether the quadrupeds' model terms (:data:`MODEL_TERMS`) are all nominal."""
        return all(getattr(self, name) == 1.0 for name in MODEL_TERMS)

    @property
    def random(self) -> bool:
        """Whether it draws random numbers (the push's step, the sensor noise)."""
        return self.push > 0.0 or self.obs_noise > 0.0

    def validate(self, directions: Sequence[str] = tuple(PUSH_DIRECTIONS)) -> Perturbation:
        """Raise ValueError naming the first bad field (``perturbation.NAME``); ``directions``:
        the push directions the robot accepts (any direction goes without a push). Returns
        ``self``."""

        def number(name: str, value: Any, low: float, strict: bool) -> None:
            ok = not isinstance(value, bool) and isinstance(value, int | float)
            ok = ok and math.isfinite(value) and (value > low if strict else value >= low)
            if not (ok and value <= HIGHS[name]):
                raise ValueError(f"perturbation.{name} must be a number with {low:g} "
                                 f"{'<' if strict else '<='} {name} <= {HIGHS[name]:g}, got "
                                 f"{brief(value)}")  # fmt: skip

        number("payload", self.payload, 0.0, False)
        if self.friction is not None:
            number("friction", self.friction, 0.0, True)
        number("latency", self.latency, 0.0, False)
        number("obs_noise", self.obs_noise, 0.0, False)
        number("motor_strength", self.motor_strength, 0.0, True)
        number("push", self.push, 0.0, False)
        for name in MODEL_TERMS:  # no passive damping is a model; no stiffness is none
            number(name, getattr(self, name), 0.0, name != "joint_damping")
        if self.push_direction not in (directions if self.push else PUSH_DIRECTIONS):
            raise ValueError(f"perturbation.push_direction must be one of "
                             f"{', '.join(directions)} on this robot, got "
                             f"{brief(self.push_direction)}")  # fmt: skip
        window = self.push_time
        if not (isinstance(window, list | tuple) and len(window) == 2
                and all(not isinstance(t, bool) and isinstance(t, int | float)
                        and math.isfinite(t) for t in window)
                and 0.0 <= window[0] <= window[1]):  # fmt: skip
            raise ValueError(f"perturbation.push_time must be [start, end] in s with "
                             f"0 <= start <= end, got {brief(window)}")  # fmt: skip
        self.push_time = (float(window[0]), float(window[1]))
        return self

    def substeps(self, decimation: int) -> int:
        """The latency in physics substeps; ValueError unless it is a whole number of them."""
        total = self.latency * decimation
        if abs(total - round(total)) > 1e-9:
            raise ValueError(f"perturbation.latency x decimation must be a whole number of "
                             f"physics substeps, got {self.latency} x {decimation}")  # fmt: skip
        return round(total)

    def actuator(self, actuator):
        """``actuator`` (:class:`~cpg_actor.robots.common.actuator.Actuator`) at this motor
        strength: PD gains, torque limit and stall torque scaled (the no-load speed kept)."""
        if self.motor_strength == 1.0 and self.kp_scale == 1.0 and self.kd_scale == 1.0:
            return actuator
        s = self.motor_strength

        def scaled(value, factor=1.0):
            factor = s * factor
            return tuple(factor * v for v in value) if isinstance(value, tuple) else factor * value

        return dataclasses.replace(
            actuator, kp=scaled(actuator.kp, self.kp_scale), kd=scaled(actuator.kd, self.kd_scale),
            torque_limit=scaled(actuator.torque_limit),
            saturation_torque=scaled(actuator.saturation_torque),
        )  # fmt: skip

    def ground_friction(self, nominal: float) -> float:
        """The foot-ground friction simulated (``nominal``: the env's ``foot_friction``)."""
        return nominal if self.friction is None else float(self.friction)

    @classmethod
    def from_value(cls, value: Any) -> Perturbation:
        """A :class:`Perturbation` from itself or a mapping of its fields (a config file's);
        unknown keys are a ValueError listing the valid ones."""
        if isinstance(value, cls):
            return value
        values = mapping_fields(cls, value, "perturbation", sequences=("push_time",))
        for name in ("payload", "latency", "obs_noise", "motor_strength", "push", "friction",
                     *MODEL_TERMS):  # fmt: skip
            if isinstance(values.get(name), int) and not isinstance(values[name], bool):
                values[name] = float(values[name])  # YAML writes 1.0 as 1
        return cls(**values)


RANDOMIZED = ("payload", "friction", "latency", "obs_noise", "motor_strength", *MODEL_TERMS)
# randomised training's pushes (the quadrupeds'): a kick of the base's horizontal velocity
TRAINING_PUSHES = ("push_velocity", "push_interval")
# what the hopper takes (its model is changed in place, not rebuilt)
HOPPER_RANDOMIZED = ("payload", "friction", "latency", "obs_noise", "motor_strength")
RANDOMIZATION_PRESETS = ("", "field")


@dataclass
class Randomization:
    """Randomised training (``env.randomize``): every episode of every env drawn its own
    payload, friction, latency, sensor noise and motor strength, and on the quadrupeds its PD
    gains, passive joint damping, armature and contact softness (:data:`MODEL_TERMS`),
    uniformly within these ranges ([low, high]; a point range is that value, drawn from
    nothing), from the env's perturbation generator; on the quadrupeds, pushes during the
    episode too (a kick of the base's horizontal velocity every ``push_interval`` s, of a size
    in ``push_velocity`` m/s, in a random direction). The defaults are the nominal robot: no
    randomisation. ``preset="field"`` fills the ranges left at their defaults with the
    robot's own training ranges (its config's ``FIELD_RANDOMIZATION``, with their sources).
    ``docs/robustness.md`` gives ranges and where they come from."""

    payload: tuple[float, float] = (0.0, 0.0)  # kg
    friction: tuple[float, float] | None = None  # None: the env's foot_friction
    latency: tuple[float, float] = (0.0, 0.0)  # control steps, drawn in whole physics substeps
    obs_noise: tuple[float, float] = (0.0, 0.0)  # x the robot's sensor noise
    motor_strength: tuple[float, float] = (1.0, 1.0)
    kp_scale: tuple[float, float] = (1.0, 1.0)  # x the drives' Kp
    kd_scale: tuple[float, float] = (1.0, 1.0)  # x the drives' Kd
    joint_damping: tuple[float, float] = (1.0, 1.0)  # x the joints' passive damping
    armature: tuple[float, float] = (1.0, 1.0)  # x the joints' armature
    contact_softness: tuple[float, float] = (1.0, 1.0)  # x the contacts' time constant
    push_velocity: tuple[float, float] = (0.0, 0.0)  # m/s: a training push's kick, no push: 0
    push_interval: tuple[float, float] = (5.0, 10.0)  # s between a training push and the next
    preset: str = ""  # "field": the robot's training ranges where none is given

    @property
    def active(self) -> bool:
        return self != Randomization()

    @property
    def pushes(self) -> bool:
        """Whether randomised training pushes the robots."""
        return self.push_velocity[1] > 0.0

    def given(self) -> list[str]:
        """The terms whose ranges differ from the defaults (what this randomisation draws)."""
        nominal = Randomization()
        names = [*RANDOMIZED, "push_velocity"]
        return [n for n in names if getattr(self, n) != getattr(nominal, n)]

    def with_defaults(self, ranges: dict[str, Any]) -> Randomization:
        """These ranges, those still at their defaults taken from ``ranges`` (a robot's
        ``FIELD_RANDOMIZATION``: name -> [low, high])."""
        nominal, values = Randomization(), {}
        for name, bounds in ranges.items():
            if getattr(self, name) == getattr(nominal, name):
                values[name] = tuple(bounds)
        return dataclasses.replace(self, **values)

    def validate(self, decimation: int) -> Randomization:
        """Raise ValueError naming the first bad range (``randomize.NAME``); returns ``self``."""
        if self.preset not in RANDOMIZATION_PRESETS:
            raise ValueError(f"randomize.preset must be one of '', 'field' (the robot's "
                             f"training ranges), got {brief(self.preset)}")  # fmt: skip
        strict = ("friction", "motor_strength", "push_interval",
                  *(n for n in MODEL_TERMS if n != "joint_damping"))  # fmt: skip
        for name in (*RANDOMIZED, *TRAINING_PUSHES):
            bounds = getattr(self, name)
            if bounds is None and name == "friction":
                continue
            ok = isinstance(bounds, list | tuple) and len(bounds) == 2 and all(
                not isinstance(b, bool) and isinstance(b, int | float) and math.isfinite(b)
                for b in bounds)  # fmt: skip
            ok = ok and bounds[0] <= bounds[1] <= HIGHS[name]
            ok = ok and (bounds[0] > 0.0 if name in strict else bounds[0] >= 0.0)
            if not ok:
                raise ValueError(f"randomize.{name} must be [low, high] with "
                                 f"0 {'<' if name in strict else '<='} low <= high <= "
                                 f"{HIGHS[name]:g}, got {brief(bounds)}")  # fmt: skip
            setattr(self, name, (float(bounds[0]), float(bounds[1])))
        for bound in self.latency:
            Perturbation(latency=bound).substeps(decimation)  # whole substeps
        return self

    def draw(self, rng: np.random.Generator, decimation: int, push: Perturbation) -> Perturbation:
        """An episode's perturbation: these fields drawn from ``rng`` (in the order of
        :data:`RANDOMIZED`; only where the range is not a point), the push's from ``push``."""

        def uniform(bounds):
            return rng.uniform(*bounds) if bounds[1] > bounds[0] else bounds[0]

        low, high = (round(b * decimation) for b in self.latency)
        substeps = int(rng.integers(low, high + 1)) if high > low else low
        return dataclasses.replace(
            push, payload=float(uniform(self.payload)),
            friction=None if self.friction is None else float(uniform(self.friction)),
            latency=substeps / decimation, obs_noise=float(uniform(self.obs_noise)),
            motor_strength=float(uniform(self.motor_strength)),
            **{name: float(uniform(getattr(self, name))) for name in MODEL_TERMS},
        )  # fmt: skip

    @classmethod
    def from_value(cls, value: Any) -> Randomization:
        """A :class:`Randomization` from itself or a mapping of its fields."""
        if isinstance(value, cls):
            return value
        if not isinstance(value, dict):
            raise ValueError(f"randomize must be a mapping of its fields, got {brief(value)}")
        names = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(str(k) for k in value if k not in names)
        if unknown:
            raise ValueError(f"unknown randomize key(s) {', '.join(unknown)}; accepted: "
                             f"{', '.join(names)}")  # fmt: skip
        return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in value.items()})


def check_perturbations(
    config: Any,
    directions: Sequence[str],
    simulators: Sequence[str],
    supported: Sequence[str] = HOPPER_RANDOMIZED,
    robot: str = "this robot",
) -> None:
    """Validate an env config's ``perturbation`` and ``randomize`` (converting mappings from
    a config file), for a robot with push ``directions`` whose ``simulators`` take them and
    which randomises the terms ``supported`` (of :data:`RANDOMIZED` and
    :data:`TRAINING_PUSHES`); ``randomize.preset`` "field" is resolved here, from the
    config's ``FIELD_RANDOMIZATION``."""
    config.perturbation = Perturbation.from_value(config.perturbation).validate(directions)
    unsupported = [
        n for n in MODEL_TERMS if n not in supported and getattr(config.perturbation, n) != 1.0
    ]
    if unsupported:
        raise ValueError(f"perturbation.{unsupported[0]} is not supported on {robot}; it takes "
                         f"{', '.join(n for n in RANDOMIZED if n in supported)}")  # fmt: skip
    randomize = Randomization.from_value(config.randomize)
    if randomize.preset == "field":
        randomize = randomize.with_defaults(getattr(config, "FIELD_RANDOMIZATION", {}))
    config.randomize = randomize
    config.perturbation.substeps(config.decimation)  # a whole number of substeps late
    push_start = config.perturbation.push_time[0]
    if config.perturbation.push and round(push_start / config.control_dt) >= config.episode_steps:
        episode = config.episode_steps * config.control_dt
        raise ValueError(f"perturbation.push_time starts at {push_start:g} s, at or after the "
                         f"end of the episode ({episode:g} s): the push would never come; give "
                         "a window that starts before it")  # fmt: skip
    config.randomize = config.randomize.validate(config.decimation)
    if config.randomize.active:
        unsupported = [n for n in config.randomize.given() if n not in supported]
        if unsupported:
            raise ValueError(f"randomize.{unsupported[0]} is not supported on {robot}; it "
                             f"randomises {', '.join(supported)}")  # fmt: skip
        nominal = Perturbation()
        given = [n for n in RANDOMIZED if getattr(config.perturbation, n) != getattr(nominal, n)]
        if given:
            raise ValueError(
                f"perturbation.{given[0]} and randomize: randomised training draws "
                f"{', '.join(n for n in RANDOMIZED if n in supported)} per episode; give one "
                "or the other"
            )
    if config.sim not in simulators and (
        not config.perturbation.nominal or config.randomize.active
    ):
        raise ValueError(f"perturbations run on {' and '.join(simulators)}; "
                         f"sim={brief(config.sim)} takes none")  # fmt: skip
