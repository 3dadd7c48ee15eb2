"""Numbers of the report: final return, smoothness, velocity share, bootstrap CIs, verdicts.

Definitions (also in ``docs/reproduction.md`` and in each report):

* **final return** of a run: the mean of the last ``FINAL_ROWS`` logged values of
  ``eval/return`` (the deterministic evaluation during training; ``charts/episode_return``,
  the mean return of the last 100 training episodes, for runs logged without it) at or
  before a step budget;
* **smoothness** of desired positions: mean over steps, joints and episodes of the squared
  second difference ``(p[t+1] - 2 p[t] + p[t-1])^2``, rad^2 per control step^2 (0 for a straight
  line; a sine of amplitude A and period n steps gives about ``A^2 (2 pi / n)^4 / 2``; a
  bang-bang signal switching between +-A gives up to ``4 A^2`` per switch);
* **velocity share**: the share of desired joint velocities with ``|v| <= 15 rad/s`` (the
  motor limit), over all steps, joints and episodes;
* **p99 |v|**: the 99th percentile of ``|desired velocity|``;
* **ratio of means with a bootstrap CI**: seeds resampled with replacement within each group,
  ``B = 10,000`` resamples, percentile interval.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

FINAL_ROWS = 10
VELOCITY_LIMIT = 15.0  # rad/s, the hopper's motor limit (paper section IV)
SUPPORTED = "supported"
NOT_SUPPORTED = "not supported"
NOT_TESTED = "not tested in this run"


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


def smoothness(desired_position: np.ndarray) -> float:
    """Mean squared second difference along axis 0 (time), rad^2; NaN rows are ignored."""
    p = np.asarray(desired_position, dtype=float)
    if p.shape[0] < 3:
        return float("nan")
    second = p[2:] - 2.0 * p[1:-1] + p[:-2]
    second = second[np.isfinite(second)]
    return float(np.mean(second**2)) if second.size else float("nan")


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


def velocity_share(desired_velocity: np.ndarray, limit: float = VELOCITY_LIMIT) -> float:
    """Share of finite desired velocities with ``|v| <= limit``."""
    v = np.asarray(desired_velocity, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.mean(np.abs(v) <= limit)) if v.size else float("nan")


def velocity_p99(desired_velocity: np.ndarray) -> float:
    v = np.asarray(desired_velocity, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.percentile(np.abs(v), 99)) if v.size else float("nan")


def mean_std(values: Sequence[float]) -> tuple[float, float]:
    """Mean and (population) standard deviation of the finite values; NaNs if none."""
    a = np.asarray(values, dtype=float)
    a = a[np.isfinite(a)]
    if a.size == 0:
        return float("nan"), float("nan")
    return float(a.mean()), float(a.std())


@dataclass
class Interval:
    estimate: float
    low: float
    high: float

    def __str__(self) -> str:
        return f"{self.estimate:.3g} [{self.low:.3g}, {self.high:.3g}]"


def bootstrap_ratio(
    numerator: Sequence[float],
    denominator: Sequence[float],
    resamples: int = 10_000,
    confidence: float = 0.95,
    seed: int = 0,
    paired: bool = False,
) -> Interval | None:
    """``mean(numerator) / mean(denominator)`` with a percentile bootstrap CI over seeds.

    ``paired``: the two are the same seeds measured twice (e.g. one policy in two
    simulators); seeds are resampled together and non-finite pairs dropped. Otherwise each
    group is resampled on its own. None when it is undefined: a group is empty, or the
    denominator's mean (or any resampled mean) is not positive (a ratio of returns is only
    meaningful for positive returns)."""
    a = np.asarray(numerator, dtype=float)
    b = np.asarray(denominator, dtype=float)
    if paired:
        keep = np.isfinite(a) & np.isfinite(b)
        a, b = a[keep], b[keep]
    else:
        a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    if a.size == 0 or b.size == 0 or b.mean() <= 0:
        return None
    rng = np.random.default_rng(seed)
    index_a = rng.integers(0, a.size, (resamples, a.size))
    index_b = index_a if paired else rng.integers(0, b.size, (resamples, b.size))
    mean_a, mean_b = a[index_a].mean(axis=1), b[index_b].mean(axis=1)
    if np.any(mean_b <= 0):
        return None
    tail = 100 * (1 - confidence) / 2
    low, high = np.percentile(mean_a / mean_b, [tail, 100 - tail])
    return Interval(float(a.mean() / b.mean()), float(low), float(high))


def bootstrap_difference(
    first: Sequence[float],
    second: Sequence[float],
    resamples: int = 10_000,
    confidence: float = 0.95,
    seed: int = 0,
) -> Interval | None:
    """``mean(first) - mean(second)`` with a percentile bootstrap CI over seeds."""
    a = np.asarray(first, dtype=float)
    b = np.asarray(second, dtype=float)
    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    if a.size == 0 or b.size == 0:
        return None
    rng = np.random.default_rng(seed)
    diff = a[rng.integers(0, a.size, (resamples, a.size))].mean(axis=1) - b[
        rng.integers(0, b.size, (resamples, b.size))
    ].mean(axis=1)
    tail = 100 * (1 - confidence) / 2
    low, high = np.percentile(diff, [tail, 100 - tail])
    return Interval(float(a.mean() - b.mean()), float(low), float(high))


# -- verdicts: (verdict, explanation) -----------------------------------------------------------
Verdict = tuple[str, str]


def verdict_reward_ratio(ratio: Interval | None, ran: bool, target: float = 6.0) -> Verdict:
    """ "About 6x the reward of Cho et al. (warm)": supported when the ratio is within a factor 2
    of ``target`` and its 95% CI lies above 1."""
    if not ran:
        return NOT_TESTED, "needs cpg-actor and cho2019-warm"
    if ratio is None:
        return NOT_SUPPORTED, "ratio undefined (Cho et al. (warm) return not positive)"
    ok = target / 2 <= ratio.estimate <= target * 2 and ratio.low > 1
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        f"ratio {ratio} (supported if within [{target / 2:g}, {target * 2:g}] and CI above 1)",
    )


def verdict_better(differences: dict[str, Interval | None], ran: bool) -> Verdict:
    """ "Open-loop CPG-Actor beats Cho et al.": the 95% CI of the difference of mean final
    returns lies above 0 for every Cho et al. variant that ran."""
    if not ran or not differences:
        return NOT_TESTED, (
            "needs cpg-actor-open-loop and cho2019-warm or cho2019, with finished training "
            "episodes logged"
        )
    ok, parts = _cis_above_zero(differences, "difference ")
    return SUPPORTED if ok else NOT_SUPPORTED, "; ".join(parts) + " (supported if CI above 0)"


def _cis_above_zero(differences: dict[str, Interval | None], prefix: str = "") -> tuple[bool, list]:
    """Whether every difference's 95% CI lies above 0 (a missing one fails), and a
    ``"vs NAME: ..."`` part per difference."""
    parts, ok = [], True
    for name, diff in differences.items():
        ok &= diff is not None and diff.low > 0
        parts.append(f"vs {name}: {prefix}{diff}" if diff is not None else f"vs {name}: no data")
    return ok, parts


def verdict_smooth(cpg: float, mlp: float, factor: float = 10.0) -> Verdict:
    """ "CPG outputs are smooth where the MLP is bang-bang": the CPG-Actor's smoothness measure is
    at least ``factor`` times smaller than the MLP actor's."""
    if not (np.isfinite(cpg) and np.isfinite(mlp)):
        return NOT_TESTED, "needs cpg-actor and mlp with eval traces"
    ok = cpg * factor <= mlp
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        f"mean squared 2nd difference {cpg:.3g} (CPG-Actor) vs {mlp:.3g} rad^2 (MLP); "
        f"supported if MLP / CPG-Actor >= {factor:g}",
    )


def verdict_near_limits(p99: float, share: float, limit: float = VELOCITY_LIMIT) -> Verdict:
    """ "Desired velocities stay near the motor limits": the 99th percentile of |v| is within
    [0.6, 1.2] x the limit (the range is used, and only just exceeded if at all)."""
    if not np.isfinite(p99):
        return NOT_TESTED, "needs cpg-actor eval traces"
    ok = 0.6 * limit <= p99 <= 1.2 * limit
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        f"p99 |v| = {p99:.3g} rad/s, {100 * share:.1f}% within +-{limit:g} rad/s; "
        f"supported if p99 in [{0.6 * limit:g}, {1.2 * limit:g}]",
    )


def verdict_hop_doubles(
    ratio: Interval | None, early_step: float, total_steps: float, threshold: float = 1.5
) -> Verdict:
    """ "The hop height about doubles with training" (paper: 1M -> 60M steps): the CPG-Actor's
    mean hop height in the deterministic evaluations at the end over that at ``early_step``
    (1M), over seeds, is >= ``threshold`` and its 95% CI lies above 1. Judged only on runs of at
    least twice ``early_step``: the hop height of an untrained agent is no baseline."""
    if total_steps < 2 * early_step:
        return NOT_TESTED, (
            f"needs runs of at least {2 * early_step:,.0f} steps (the paper compares "
            f"{early_step:,.0f} steps with the end); this run: {total_steps:,.0f}"
        )
    if ratio is None:
        return NOT_TESTED, f"needs cpg-actor hop heights logged at {early_step:,.0f} steps"
    ok = ratio.estimate >= threshold and ratio.low > 1
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        f"hop height at the end / at {early_step:,.0f} steps: x{ratio} (supported if "
        f">= x{threshold:g} and CI above 1)",
    )


def verdict_best_during_training(differences: dict[str, Interval | None], ran: bool) -> Verdict:
    """ "The CPG-Actor performs best during training": the mean evaluation return over the
    whole run (the area under the curve, per seed) is above every other variant's, the 95% CI
    of each difference above 0."""
    if not ran or not differences:
        return NOT_TESTED, "needs cpg-actor and another variant with evaluation curves"
    ok, parts = _cis_above_zero(differences)
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        "mean eval return over the run, difference " + "; ".join(parts)
        + " (supported if every CI is above 0)",
    )  # fmt: skip


def verdict_cho_flat(
    cpg: dict[str, float], cho: dict[str, dict[str, float]], factor: float = 3.0
) -> Verdict:
    """ "Cho et al.'s theta_dot and r_ddot stay almost flat (not responsive to the
    environment) where the CPG-Actor's are reshaped by feedback" (paper section V): the
    CPG-Actor's :func:`variability` of both signals is at least ``factor`` times every Cho
    variant's. ``cpg`` and each ``cho[variant]`` map ``theta_dot`` and ``r_ddot`` to it."""
    names = ("theta_dot", "r_ddot")
    runs = {k: v for k, v in cho.items() if all(np.isfinite(v[n]) for n in names)}
    if not all(np.isfinite(cpg[n]) for n in names) or not runs:
        return NOT_TESTED, "needs cpg-actor and a Cho et al. variant with CPG traces"
    ok = all(cpg[n] >= factor * values[n] for values in runs.values() for n in names)
    parts = [
        f"{variant}: theta_dot {values['theta_dot']:.3g} rad/s, r_ddot "
        f"{values['r_ddot']:.3g} rad/s^2"
        for variant, values in runs.items()
    ]
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        f"std over an episode: CPG-Actor theta_dot {cpg['theta_dot']:.3g} rad/s, r_ddot "
        f"{cpg['r_ddot']:.3g} rad/s^2; " + "; ".join(parts)
        + f" (supported if the CPG-Actor's are >= {factor:g}x every Cho variant's)",
    )  # fmt: skip


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
