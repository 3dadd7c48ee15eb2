"""What the robustness suite runs, declared per robot: :class:`PerturbationTable`, its
:class:`PerturbationAxis` entries and :func:`standard_axes`, the levels every robot here
uses."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from cpg_actor.robots.common.perturbation.values import Perturbation


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
