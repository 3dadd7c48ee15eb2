"""A run's numbers from its logged curves and its CPG traces, for a study's report.

* **final return** of a run: the mean of the last ``FINAL_ROWS`` logged values of
  ``eval/return`` (the deterministic evaluation during training; ``charts/episode_return``,
  the mean return of the last 100 training episodes, for runs logged without it) at or
  before a step budget (:func:`final_return`); its best moving mean (:func:`peak_return`);
* **variability** of a CPG signal (theta_dot, r_ddot) within an episode, and how often a
  bounded feedback (xi, kappa) sits at its bound (:func:`variability`, :func:`bound_share`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

FINAL_ROWS = 10


def final_return(
    steps: Sequence[float],
    returns: Sequence[float | None],
    at_step: float | None = None,
    rows: int = FINAL_ROWS,
) -> float:
    """Mean of the last ``rows`` finite returns logged at or before ``at_step`` (NaN if none)."""
    steps_a = np.asarray(steps, dtype=float)
    values = np.array([np.nan if v is None else v for v in returns], dtype=float)
    keep = np.isfinite(values)
    if at_step is not None:
        keep &= steps_a <= at_step
    values = values[keep]
    return float(values[-rows:].mean()) if values.size else float("nan")


def curve_mean(values: Sequence[float | None]) -> float:
    """Mean of the finite values of a logged curve (evaluations are evenly spaced in steps)."""
    a = np.array([np.nan if v is None else v for v in values], dtype=float)
    a = a[np.isfinite(a)]
    return float(a.mean()) if a.size else float("nan")


def peak_return(
    steps: Sequence[float], returns: Sequence[float | None], rows: int = FINAL_ROWS
) -> tuple[float, float]:
    """The best moving mean of ``rows`` consecutive finite returns of a logged curve, and the
    step of the last return in that window: ``(peak, step)``, NaNs if the curve has none.
    Next to :func:`final_return` (the same mean over the last ``rows``), it shows whether a
    run was still improving at the end or had stopped (or fallen back) earlier."""
    steps_a = np.asarray(steps, dtype=float)
    values = np.array([np.nan if v is None else v for v in returns], dtype=float)
    keep = np.isfinite(values)
    steps_a, values = steps_a[keep], values[keep]
    if not values.size:
        return float("nan"), float("nan")
    window = min(rows, values.size)
    # each window's mean as final_return takes it: the last window equals it exactly
    means = np.array([values[i : i + window].mean() for i in range(values.size - window + 1)])
    best = int(np.argmax(means))
    return float(means[best]), float(steps_a[best + window - 1])


def exploration_std(row: dict[str, Any]) -> float:
    """The policy's Gaussian std at a logged row: the mean over the action's entries of
    ``exp(policy/log_std_i)`` (in the action's units: rad for joint targets), NaN if the row
    has none."""
    logs = [v for k, v in row.items() if k.startswith("policy/log_std_") and v is not None]
    return float(np.mean(np.exp(logs))) if logs else float("nan")


def variability(signal: np.ndarray, skip: int = 50) -> float:
    """How much a CPG signal (theta_dot, r_ddot; ``(T, E, N)``) moves within an episode: its
    standard deviation over time after the first ``skip`` steps (the start-up transient),
    mean over episodes and oscillators. 0 for a signal that stays flat."""
    x = np.asarray(signal, dtype=float)
    if x.shape[0] <= skip + 1:
        return float("nan")
    std = np.nanstd(x[skip:], axis=0)
    return float(np.nanmean(std)) if np.isfinite(std).any() else float("nan")


def bound_share(feedback: np.ndarray, bound: float, level: float = 0.95) -> float:
    """Share of feedback values (xi or kappa traces, any shape) at ``level`` or more of their
    bound (``xi_scale``, ``kappa_scale``): near 1 for a bang-bang feedback."""
    x = np.abs(np.asarray(feedback, dtype=float))
    x = x[np.isfinite(x)]
    return float(np.mean(x >= level * bound)) if x.size and bound > 0 else float("nan")
