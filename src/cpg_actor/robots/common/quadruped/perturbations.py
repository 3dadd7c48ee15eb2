"""A quadruped's perturbations for the robustness suite (``docs/robustness.md``): pushes on
the base forward, backward and sideways (to the left), and the standard payload, friction,
latency, sensor noise and motor strength levels of
:func:`~cpg_actor.robots.common.perturbation.standard_axes`, sized by the robot's moving mass;
its gait cycle is the stride of the first foot, from one touchdown to the next, and the
cycle's value the base's mean forward speed over it."""

from __future__ import annotations

import numpy as np

from cpg_actor.robots.common.perturbation import PerturbationTable, standard_axes

PUSHES = {"push_forward": "forward", "push_backward": "backward", "push_sideways": "left"}


def strides(traces: dict[str, np.ndarray], env: int) -> tuple[np.ndarray, np.ndarray]:
    """Episode ``env``'s whole strides: the touchdowns of the first foot that bound them (n + 1
    steps) and the base's mean forward speed over each (n, m/s)."""
    speed = np.asarray(traces["base_forward_speed"], dtype=float)[:, env]
    contact = np.asarray(traces["foot_contact"], dtype=float)[:, env, 0]
    steps = int(np.isfinite(speed).sum())  # the rows after the episode ended are NaN
    touching = contact[:steps] > 0.5
    starts = np.flatnonzero(touching[1:] & ~touching[:-1]) + 1
    means = [speed[a:b].mean() for a, b in zip(starts[:-1], starts[1:], strict=True)]
    return starts, np.asarray(means, dtype=float)


def perturbation_table(moving_mass: float, foot_friction: float) -> PerturbationTable:
    axes = standard_axes(moving_mass, PUSHES, foot_friction)
    return PerturbationTable(axes, metrics=("speed_error", "fell"), cycles=strides,
                             cycle_name="stride speed (m/s)", cycle_floor=0.05)  # fmt: skip
