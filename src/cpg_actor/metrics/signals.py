"""What an evaluation's desired joint positions (the commands the env tracked) show: smoothness,
desired velocity, time at a joint stop.

* **desired position**: the joint position command the env actually tracked, i.e. the
  agent's command after the env clipped it to the action space (the joint limits); for Cho
  et al. ``nominal pose + x`` after that clip. Every agent's traces hold it as
  ``desired_position`` (:func:`cpg_actor.training.evaluation.evaluate`);
* **desired velocity** (every agent alike): the finite difference of the desired positions
  over the control period, ``(p[t] - p[t-1]) / dt`` (:func:`desired_velocity`). The first
  step of an episode has no previous command of the agent's (the env's reset pose is not
  the agent's), so it is left out (NaN);
* **smoothness** of desired positions: mean over steps, joints and episodes of the squared
  second difference ``(p[t+1] - 2 p[t] + p[t-1])^2``, rad^2 per control step^2 (0 for a straight
  line; a sine of amplitude A and period n steps gives about ``A^2 (2 pi / n)^4 / 2``; a
  bang-bang signal switching between +-A gives up to ``4 A^2`` per switch);
* **velocity share**: the share of desired joint velocities with ``|v| <= limit`` (a motor
  limit: the hopper's is 15 rad/s), over all steps, joints and episodes;
* **p99 |v|**: the 99th percentile of ``|desired velocity|``;
* **time at a joint stop**: the share of control steps at which a desired joint position
  sent lies within ``JOINT_STOP_TOLERANCE`` of its joint's limit (the action space's bound).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

# rad: a desired position this close to a joint limit is "at the stop"; the env clips in
# float32 (1e-7 rad off the float64 limit), a command pushed past the limit sits on it exactly
JOINT_STOP_TOLERANCE = 1e-3


def smoothness(desired_position: np.ndarray) -> float:
    """Mean squared second difference along axis 0 (time), rad^2; NaN rows are ignored."""
    p = np.asarray(desired_position, dtype=float)
    if p.shape[0] < 3:
        return float("nan")
    second = p[2:] - 2.0 * p[1:-1] + p[:-2]
    second = second[np.isfinite(second)]
    return float(np.mean(second**2)) if second.size else float("nan")


def velocity_share(desired_velocity: np.ndarray, limit: float) -> float:
    """Share of finite desired velocities with ``|v| <= limit``."""
    v = np.asarray(desired_velocity, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.mean(np.abs(v) <= limit)) if v.size else float("nan")


def velocity_p99(desired_velocity: np.ndarray) -> float:
    v = np.asarray(desired_velocity, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.percentile(np.abs(v), 99)) if v.size else float("nan")


def desired_velocity(desired_position: np.ndarray, dt: float) -> np.ndarray:
    """The desired velocity of every agent: the finite difference of the desired positions
    sent, ``(p[t] - p[t-1]) / dt`` along axis 0 (time), the same shape; row 0 (the first step
    of the episode, which has no previous command of the agent's) is NaN."""
    p = np.asarray(desired_position, dtype=float)
    if not dt > 0:
        raise ValueError(f"the control period dt must be > 0, got {dt!r}")
    v = np.full_like(p, np.nan)
    v[1:] = (p[1:] - p[:-1]) / dt
    return v


def joint_stop_share(
    desired_position: np.ndarray,
    low: Sequence[float],
    high: Sequence[float],
    tolerance: float = JOINT_STOP_TOLERANCE,
) -> float:
    """Share of control steps (rows of ``(T, ..., J)`` desired positions, NaN rows left out)
    at which the desired position of any joint lies within ``tolerance`` of its limit
    ``low[j]`` or ``high[j]`` (or beyond it)."""
    p = np.asarray(desired_position, dtype=float)
    low_a, high_a = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    if p.shape[-1] != low_a.size or low_a.shape != high_a.shape:
        raise ValueError(
            f"one limit per joint needed: positions have {p.shape[-1]} joints, limits "
            f"{low_a.size} and {high_a.size}"
        )
    steps = p.reshape(-1, p.shape[-1])
    steps = steps[np.isfinite(steps).all(axis=1)]
    if not steps.size:
        return float("nan")
    at_stop = (steps <= low_a + tolerance) | (steps >= high_a - tolerance)
    return float(np.mean(at_stop.any(axis=1)))
