"""How long a gait takes to come back after a push: pure functions of an episode's gait
cycles (a robot's ``PerturbationTable.cycles``: the hops of the hopper, the strides of a
quadruped) and of the same episode without the push."""

from __future__ import annotations

import numpy as np

TOLERANCE = 0.1  # a cycle within 10 % of the nominal one is back
STEADY_CYCLES = 2  # cycles in a row, to the end of the episode, that make a gait back


def nominal_cycle(bounds: np.ndarray, values: np.ndarray, after: int) -> float:
    """The nominal episode's cycle after step ``after``: the median value of its whole cycles
    that start then or later; NaN with fewer than :data:`STEADY_CYCLES` (no gait)."""
    later = np.asarray(values, dtype=float)[np.asarray(bounds)[:-1] >= after]
    return float(np.median(later)) if later.size >= STEADY_CYCLES else float("nan")


def recovery_steps(bounds: np.ndarray, values: np.ndarray, push: int, reference: float,
                   floor: float = 0.0) -> float | None:  # fmt: skip
    """Control steps from the ``push`` until the gait is back: until the start of the first
    cycle from which every cycle to the episode's end is within :data:`TOLERANCE` of
    ``reference`` (or ``floor``, where larger), at least :data:`STEADY_CYCLES` of them; 0 if
    the cycle the push came in already is. None: not recovered (no such cycles after the
    push). NaN when there is no nominal gait to come back to (``reference`` NaN)."""
    if not np.isfinite(reference):
        return float("nan")
    bounds, values = np.asarray(bounds), np.asarray(values, dtype=float)
    ends = bounds[1:]
    after = np.flatnonzero(ends > push)  # the cycles not over before the push
    if after.size < STEADY_CYCLES:
        return None
    within = np.abs(values[after] - reference) <= max(TOLERANCE * abs(reference), floor)
    bad = np.flatnonzero(~within)
    first = 0 if bad.size == 0 else bad[-1] + 1  # the steady run to the end starts here
    if after.size - first < STEADY_CYCLES:
        return None
    return float(max(0, int(bounds[after[first]]) - push))
