"""Perturbations of a robot and its world, part of every env's config (``env.perturbation``).

A :class:`Perturbation` is a pure function of its values and the episode's seed: the physical
ones (payload, ground friction, motor strength) change the model the simulator is built from,
latency changes when a command reaches the drives, and the random ones (when a push comes,
the sensor noise) are drawn from generators of their own, seeded from each env's seed, so that
the env's own draws (the start pose, the command) are those of the nominal env. The nominal
values (the defaults) change nothing: an env with them computes exactly what it computed
before perturbations existed.

Each robot declares the levels the robustness suite runs (:class:`PerturbationTable`, its env
config's ``perturbation_table()``); the suite (:mod:`cpg_actor.robustness`) knows no robot.
``docs/robustness.md`` says what each one does and where its levels come from.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

# the push's direction: along the hopper's rail, or in the quadruped base's heading frame
PUSH_DIRECTIONS = {
    "up": (0.0, 0.0, 1.0),
    "down": (0.0, 0.0, -1.0),
    "forward": (1.0, 0.0, 0.0),
    "backward": (-1.0, 0.0, 0.0),
    "left": (0.0, 1.0, 0.0),
    "right": (0.0, -1.0, 0.0),
}
# mixed into each env's seed for the perturbations' own generators: their draws never touch
# the env's (start poses, commands)
SEED_KEY = 0x7E57B0D5


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

    @property
    def nominal(self) -> bool:
        """Whether it changes nothing (the push's direction and time then do not matter)."""
        return (self.payload == 0.0 and self.friction is None and self.latency == 0.0
                and self.obs_noise == 0.0 and self.motor_strength == 1.0
                and self.push == 0.0)  # fmt: skip

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
            if not ok:
                raise ValueError(f"perturbation.{name} must be a finite number "
                                 f"{'>' if strict else '>='} {low:g}, got {value!r}")  # fmt: skip

        number("payload", self.payload, 0.0, False)
        if self.friction is not None:
            number("friction", self.friction, 0.0, True)
        number("latency", self.latency, 0.0, False)
        number("obs_noise", self.obs_noise, 0.0, False)
        number("motor_strength", self.motor_strength, 0.0, True)
        number("push", self.push, 0.0, False)
        if self.push_direction not in (directions if self.push else PUSH_DIRECTIONS):
            raise ValueError(f"perturbation.push_direction must be one of "
                             f"{', '.join(directions)} on this robot, got "
                             f"{self.push_direction!r}")  # fmt: skip
        window = self.push_time
        if not (isinstance(window, list | tuple) and len(window) == 2
                and all(not isinstance(t, bool) and isinstance(t, int | float)
                        and math.isfinite(t) for t in window)
                and 0.0 <= window[0] <= window[1]):  # fmt: skip
            raise ValueError(f"perturbation.push_time must be [start, end] in s with "
                             f"0 <= start <= end, got {window!r}")  # fmt: skip
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
        if self.motor_strength == 1.0:
            return actuator
        s = self.motor_strength

        def scaled(value):
            return tuple(s * v for v in value) if isinstance(value, tuple) else s * value

        return dataclasses.replace(
            actuator, kp=scaled(actuator.kp), kd=scaled(actuator.kd),
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
        if not isinstance(value, dict):
            raise ValueError(f"perturbation must be a mapping of its fields, got {value!r}")
        names = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(str(k) for k in value if k not in names)
        if unknown:
            raise ValueError(f"unknown perturbation key(s) {', '.join(unknown)}; accepted: "
                             f"{', '.join(names)}")  # fmt: skip
        values = dict(value)
        if isinstance(values.get("push_time"), list):
            values["push_time"] = tuple(values["push_time"])
        for name in ("payload", "latency", "obs_noise", "motor_strength", "push", "friction"):
            if isinstance(values.get(name), int) and not isinstance(values[name], bool):
                values[name] = float(values[name])  # YAML writes 1.0 as 1
        return cls(**values)


# -- what the robustness suite runs, declared per robot --------------------------------------


@dataclass(frozen=True)
class PerturbationAxis:
    """One perturbation of the suite: ``field`` of :class:`Perturbation` at increasing
    ``levels`` (the nominal value, ``nominal``, is not among them), with ``fixed`` values of
    other fields (a push's direction)."""

    field: str
    levels: tuple[float, ...]
    unit: str  # "" for a multiple or a count
    description: str
    nominal: float = 0.0  # the field's value that changes nothing, drawn at the nominal point
    fixed: dict[str, Any] = dataclasses.field(default_factory=dict)

    def perturbation(self, level: float) -> Perturbation:
        return Perturbation(**{**self.fixed, self.field: level})


@dataclass(frozen=True)
class PerturbationTable:
    """A robot's perturbations for the robustness suite (by name, in the order it runs them),
    the episode metrics it reports per level, and its gait cycle: ``cycles(traces, env)``
    gives, for episode ``env`` of an evaluation's traces, the control steps that bound its
    whole cycles (hops, strides; n + 1 steps for n cycles) and each cycle's value (the hop's
    apex, the stride's speed), from which the suite reads how long a push takes to be
    recovered from (within 10 % of the nominal episode's cycle, or within ``cycle_floor`` of
    it, in the value's unit, where that is larger)."""

    axes: dict[str, PerturbationAxis]
    metrics: tuple[str, ...]
    cycles: Callable[[dict[str, np.ndarray], int], tuple[np.ndarray, np.ndarray]]
    cycle_name: str  # the cycle's value in words, with its unit
    cycle_floor: float = 0.0


def standard_axes(moving_mass: float, push_directions: dict[str, str],
                  nominal_friction: float) -> dict[str, PerturbationAxis]:  # fmt: skip
    """The suite's perturbations of a robot of ``moving_mass`` kg, its pushes by name (->
    direction), its nominal foot friction (drawn as the friction's nominal point).

    * pushes: impulses giving the moving mass 0.25, 0.5, 1 and 1.5 m/s (legged_gym pushes
      its robots to 1 m/s, Rudin et al. 2021);
    * payload: 10, 20, 30 and 50 % of the moving mass (the issue's range);
    * friction: 0.2 (ice-like, wet tiles) to 1.5 (rubber on rough ground);
    * latency: half a control step to 3 steps;
    * sensor noise: 0.5 to 4 x the robot's sensor noise (its task's ``SENSOR_NOISE``);
    * motor strength: 0.6 to 1.2 (the issue's range).
    """
    pushes = tuple(round(moving_mass * dv, 1) for dv in (0.25, 0.5, 1.0, 1.5))
    axes = {
        name: PerturbationAxis("push", pushes, "N s",
                               f"an impulse {direction} on the robot over one control step, "
                               "at a random time 1-2 s into the episode",
                               fixed={"push_direction": direction})
        for name, direction in push_directions.items()
    }  # fmt: skip
    payloads = tuple(round(moving_mass * share, 2) for share in (0.1, 0.2, 0.3, 0.5))
    axes["payload"] = PerturbationAxis("payload", payloads, "kg",
                                       "mass added to the hip or base")  # fmt: skip
    axes["friction"] = PerturbationAxis("friction", (0.2, 0.4, 0.6, 1.5), "",
                                        "foot-ground sliding friction",
                                        nominal=nominal_friction)  # fmt: skip
    axes["latency"] = PerturbationAxis("latency", (0.5, 1.0, 2.0, 3.0), "control steps",
                                       "the command reaches the drives this late")  # fmt: skip
    axes["obs_noise"] = PerturbationAxis("obs_noise", (0.5, 1.0, 2.0, 4.0), "x sensor noise",
                                         "Gaussian noise on the sensed observations")  # fmt: skip
    axes["motor_strength"] = PerturbationAxis("motor_strength", (0.6, 0.7, 0.8, 1.2), "x",
                                              "PD gains, torque limit and stall torque scaled",
                                              nominal=1.0)  # fmt: skip
    return axes


# -- randomised training -----------------------------------------------------------------------

RANDOMIZED = ("payload", "friction", "latency", "obs_noise", "motor_strength")


@dataclass
class Randomization:
    """Randomised training (``env.randomize``): every episode of every env drawn its own
    payload, friction, latency, sensor noise and motor strength, uniformly within these ranges
    ([low, high]; a point range is that value, drawn from nothing), from the env's
    perturbation generator. The defaults are the nominal robot: no randomisation.
    ``docs/robustness.md`` gives ranges and where they come from."""

    payload: tuple[float, float] = (0.0, 0.0)  # kg
    friction: tuple[float, float] | None = None  # None: the env's foot_friction
    latency: tuple[float, float] = (0.0, 0.0)  # control steps, drawn in whole physics substeps
    obs_noise: tuple[float, float] = (0.0, 0.0)  # x the robot's sensor noise
    motor_strength: tuple[float, float] = (1.0, 1.0)

    @property
    def active(self) -> bool:
        return self != Randomization()

    def validate(self, decimation: int) -> Randomization:
        """Raise ValueError naming the first bad range (``randomize.NAME``); returns ``self``."""
        lows = {"payload": 0.0, "friction": 0.0, "latency": 0.0, "obs_noise": 0.0,
                "motor_strength": 0.0}  # fmt: skip
        for name in RANDOMIZED:
            bounds = getattr(self, name)
            if bounds is None and name == "friction":
                continue
            strict = name in ("friction", "motor_strength")
            ok = isinstance(bounds, list | tuple) and len(bounds) == 2 and all(
                not isinstance(b, bool) and isinstance(b, int | float) and math.isfinite(b)
                for b in bounds)  # fmt: skip
            ok = ok and bounds[0] <= bounds[1]
            ok = ok and (bounds[0] > lows[name] if strict else bounds[0] >= lows[name])
            if not ok:
                raise ValueError(f"randomize.{name} must be [low, high] with "
                                 f"{lows[name]:g} {'<' if strict else '<='} low <= high, got "
                                 f"{bounds!r}")  # fmt: skip
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
        )  # fmt: skip

    @classmethod
    def from_value(cls, value: Any) -> Randomization:
        """A :class:`Randomization` from itself or a mapping of its fields."""
        if isinstance(value, cls):
            return value
        if not isinstance(value, dict):
            raise ValueError(f"randomize must be a mapping of its fields, got {value!r}")
        names = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(str(k) for k in value if k not in names)
        if unknown:
            raise ValueError(f"unknown randomize key(s) {', '.join(unknown)}; accepted: "
                             f"{', '.join(names)}")  # fmt: skip
        return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in value.items()})


def check_perturbations(config: Any, directions: Sequence[str], simulators: Sequence[str]) -> None:
    """Validate an env config's ``perturbation`` and ``randomize`` (converting mappings from
    a config file), for a robot with push ``directions`` whose ``simulators`` take them."""
    config.perturbation = Perturbation.from_value(config.perturbation).validate(directions)
    config.perturbation.substeps(config.decimation)  # a whole number of substeps late
    config.randomize = Randomization.from_value(config.randomize).validate(config.decimation)
    if config.randomize.active:
        nominal = Perturbation()
        given = [n for n in RANDOMIZED if getattr(config.perturbation, n) != getattr(nominal, n)]
        if given:
            raise ValueError(
                f"perturbation.{given[0]} and randomize: randomised training draws "
                f"{', '.join(RANDOMIZED)} per episode; give one or the other"
            )
    if config.sim not in simulators and (
        not config.perturbation.nominal or config.randomize.active
    ):
        raise ValueError(f"perturbations run on {' and '.join(simulators)}; "
                         f"sim={config.sim!r} takes none")  # fmt: skip


# -- at run time -------------------------------------------------------------------------------


class CommandDelay:
    """The commands of N robots applied late: ``schedule(desired)`` takes this step's commands
    (N, J) and gives what the drives track at each of the step's ``decimation`` substeps
    (N, decimation, J). Robot i's commands arrive ``latency[i]`` physics substeps late
    (:meth:`set_latency`; a perturbation's for all at first, ``longest`` substeps at most).
    Before an episode's first command arrives the drives track its start command
    (:meth:`reset`)."""

    def __init__(self, latency: int, decimation: int, num_envs: int, num_joints: int,
                 longest: int | None = None) -> None:  # fmt: skip
        self.decimation = decimation
        longest = latency if longest is None else max(longest, latency)
        # the last commands, oldest first: enough for the longest delay
        self.history = np.zeros((longest // decimation + 2, num_envs, num_joints))
        self.latency = np.full(num_envs, latency, dtype=np.int64)
        self._rows = np.arange(num_envs)

    @property
    def steps(self) -> np.ndarray:
        """(N,) whole control steps of each robot's delay."""
        return self.latency // self.decimation

    def set_latency(self, index, substeps) -> None:
        self.latency[index] = substeps

    def reset(self, index, command) -> None:
        """Robots ``index`` start an episode with the drives on ``command`` (k, J) or (J,)."""
        self.history[:, index] = command

    def schedule(self, desired: np.ndarray) -> np.ndarray:
        self.history[:-1] = self.history[1:].copy()
        self.history[-1] = desired
        steps, substeps = np.divmod(self.latency, self.decimation)
        newest = len(self.history) - 1
        before = self.history[newest - steps - 1, self._rows]  # the step before's command
        arrived = self.history[newest - steps, self._rows]  # this step's, `steps` steps ago
        early = np.arange(self.decimation)[None, :] < substeps[:, None]  # (N, decimation)
        return np.where(early[:, :, None], before[:, None], arrived[:, None])

    def get_state(self) -> np.ndarray:
        return self.history.copy()

    def set_state(self, history: np.ndarray) -> None:
        np.copyto(self.history, np.asarray(history, dtype=np.float64))


def perturbation_seed(seed: int | None) -> np.random.SeedSequence | None:
    """The seed of an env's perturbation generator, from the env's own seed (None: random)."""
    return None if seed is None else np.random.SeedSequence([SEED_KEY, int(seed)])


class EpisodeDraws:
    """The random part of the perturbations of N envs: each env's generator of its own (seeded
    from the env's seed by :func:`perturbation_seed`), each episode's perturbation under
    randomised training, the control step of each episode's push and the sensor noise. With
    nothing to draw it does nothing."""

    def __init__(self, config: Any, num_envs: int, sensor_noise: Sequence[float]) -> None:
        perturbation, randomize = config.perturbation, config.randomize
        self.perturbation, self.randomize = perturbation, randomize
        self.decimation = config.decimation
        self.active = perturbation.random or randomize.active
        self.num_envs = num_envs
        first, last = (round(t / config.control_dt) for t in perturbation.push_time)
        self.window = (first, last)
        self.sensor_noise = np.asarray(sensor_noise, dtype=np.float64)
        self.noisy = np.flatnonzero(self.sensor_noise > 0)
        self.rngs: list[np.random.Generator] = []
        self.push_step = np.full(num_envs, -1, dtype=np.int64)
        # each env's episode perturbation (randomised training: drawn by start())
        self.episodes = [perturbation] * num_envs

    def seed(self, seeds: Sequence[int | None]) -> None:
        """New generators, env i's from ``seeds[i]``."""
        if self.active:
            self.rngs = [np.random.default_rng(perturbation_seed(s)) for s in seeds]

    def start(self, index) -> np.ndarray:
        """Draw the episodes the envs ``index`` start: under randomised training their
        perturbations (:attr:`episodes`), then their push steps. Returns ``index`` as an
        array."""
        index = np.atleast_1d(index)
        if not self.active:
            return index
        for i in index:
            rng = self.rngs[i]
            if self.randomize.active:
                self.episodes[i] = self.randomize.draw(rng, self.decimation, self.perturbation)
            if self.perturbation.push:
                self.push_step[i] = rng.integers(self.window[0], self.window[1] + 1)
        return index

    def pushed(self, elapsed: np.ndarray) -> np.ndarray:
        """(N,) bool: the envs pushed during the control step after ``elapsed`` steps."""
        return (self.push_step == elapsed) & self.active & (self.perturbation.push > 0.0)

    def observe(self, obs: np.ndarray, index=None) -> np.ndarray:
        """``obs`` (N, D) as the sensors read it: noise added to rows ``index`` (default all),
        in place (float32)."""
        if not self.active or self.noisy.size == 0:
            return obs
        rows = range(self.num_envs) if index is None else np.atleast_1d(index)
        for i in rows:
            level = self.episodes[i].obs_noise
            if level > 0.0:
                std = level * self.sensor_noise[self.noisy]
                obs[i, self.noisy] += self.rngs[i].normal(0.0, std).astype(obs.dtype)
        return obs

    def get_state(self) -> dict[str, Any]:
        """The generators and the episode perturbations, as plain Python values (the push
        steps, an array, are the env's to save: :attr:`push_step`)."""
        return {"rngs": [rng.bit_generator.state for rng in self.rngs],
                "episodes": [dataclasses.asdict(p) for p in self.episodes]}  # fmt: skip

    def set_state(self, state: dict[str, Any], push_step=None) -> None:
        self.rngs = []
        for saved in state["rngs"]:
            rng = np.random.default_rng()
            rng.bit_generator.state = saved
            self.rngs.append(rng)
        if push_step is not None:
            np.copyto(self.push_step, np.asarray(push_step, dtype=np.int64))
        self.episodes = [Perturbation.from_value(dict(p)) for p in state["episodes"]]


def push_force(perturbation: Perturbation, control_dt: float) -> np.ndarray:
    """The push's force (3,), N, in its direction's frame: the impulse over one control step."""
    return (perturbation.push / control_dt) * np.asarray(PUSH_DIRECTIONS[
        perturbation.push_direction])  # fmt: skip


__all__ = [
    "CommandDelay", "EpisodeDraws", "PUSH_DIRECTIONS", "Perturbation", "PerturbationAxis",
    "PerturbationTable", "Randomization", "check_perturbations", "push_force", "standard_axes",
]  # fmt: skip
