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

from cpg_actor.robots.common.perturbation.runtime import (
    CommandDelay,
    EpisodeDraws,
    perturbation_seed,
    push_force,
)
from cpg_actor.robots.common.perturbation.table import (
    PerturbationAxis,
    PerturbationTable,
    standard_axes,
)
from cpg_actor.robots.common.perturbation.values import (
    PUSH_DIRECTIONS,
    RANDOMIZED,
    Perturbation,
    Randomization,
    check_perturbations,
)

__all__ = [
    "CommandDelay", "EpisodeDraws", "PUSH_DIRECTIONS", "Perturbation", "PerturbationAxis",
    "PerturbationTable", "RANDOMIZED", "Randomization", "check_perturbations",
    "perturbation_seed", "push_force", "standard_axes",
]  # fmt: skip
