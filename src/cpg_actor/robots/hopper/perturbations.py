"""The hopper's perturbations for the robustness suite (``docs/robustness.md``): pushes up and
down the rail, and the standard payload, friction, latency, sensor noise and motor strength
levels of :func:`~cpg_actor.robots.common.perturbation.standard_axes`; its gait cycle is the
hop, from one touchdown to the next, and the cycle's value the hop's apex."""

from __future__ import annotations

import numpy as np

from cpg_actor.robots.common.perturbation import PerturbationTable, standard_axes
from cpg_actor.robots.hopper import description as robot

TOUCHING = 0.005  # m: a foot this close to the ground touches it (the quadruped's margin)


def touchdowns(touching: np.ndarray) -> np.ndarray:
    """The steps at which a foot that did not touch the ground touches it, from (T,) bools."""
    touching = np.asarray(touching, dtype=bool)
    return np.flatnonzero(touching[1:] & ~touching[:-1]) + 1


def hops(traces: dict[str, np.ndarray], env: int) -> tuple[np.ndarray, np.ndarray]:
    """Episode ``env``'s whole hops: the touchdowns that bound them (n + 1 steps: hop k from
    touchdown k to touchdown k + 1) and each one's apex (n), the highest hip height in it
    above the standing one (m)."""
    hip = np.asarray(traces["hip_height"], dtype=float)[:, env]
    foot = np.asarray(traces["foot_height"], dtype=float)[:, env]
    steps = int(np.isfinite(hip).sum())  # the rows after the episode ended are NaN
    starts = touchdowns(foot[:steps] < TOUCHING)
    standing = float(traces.get("standing_hip_height", 0.0))
    apex = [hip[a:b].max() - standing for a, b in zip(starts[:-1], starts[1:], strict=True)]
    return starts, np.asarray(apex, dtype=float)


def perturbation_table() -> PerturbationTable:
    from cpg_actor.robots.hopper.config import HopperConfig

    axes = standard_axes(robot.TOTAL_MASS, {"push_up": "up", "push_down": "down"},
                         HopperConfig().foot_friction)  # fmt: skip
    return PerturbationTable(axes, metrics=("hop_height",), cycles=hops,
                             cycle_name="hop apex (m)", cycle_floor=0.01)  # fmt: skip
