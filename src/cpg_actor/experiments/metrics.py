"""Numbers of the report: final return, smoothness, desired velocity, time at a joint stop,
bootstrap CIs, verdicts.

Definitions (also in ``docs/reproduction.md`` and in each report):

* **final return** of a run: the mean of the last ``FINAL_ROWS`` logged values of
  ``eval/return`` (the deterministic evaluation during training; ``charts/episode_return``,
  the mean return of the last 100 training episodes, for runs logged without it) at or
  before a step budget;
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
* **velocity share**: the share of desired joint velocities with ``|v| <= 15 rad/s`` (the
  motor limit), over all steps, joints and episodes;
* **p99 |v|**: the 99th percentile of ``|desired velocity|``;
* **time at a joint stop**: the share of control steps at which a desired joint position
  sent lies within ``JOINT_STOP_TOLERANCE`` of its joint's limit (the action space's bound);
* **per seed, then over seeds**: each number above is one value per run (seed); a variant's
  value is the median over its seeds with a bootstrap CI, or, for returns and hop heights in
  the claims, the mean;
* **bootstrap**: percentile intervals, ``RESAMPLES`` resamples of the seeds with replacement
  from a generator seeded with ``BOOTSTRAP_SEED`` (the same numbers every time); unpaired
  (each variant resampled on its own) between variants, paired (one draw of seed indices
  applied to both) when the same seeds are measured twice;
* **not tested**: a verdict (and an interval) needs at least ``MIN_SEEDS`` seeds with data on
  every side; with fewer it is "not tested", never a verdict.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

FINAL_ROWS = 10
VELOCITY_LIMIT = 15.0  # rad/s, the hopper's motor limit (paper section IV)
SUPPORTED = "supported"
NOT_SUPPORTED = "not supported"
NOT_TESTED = "not tested in this run"
MIN_SEEDS = 3  # fewer seeds on a side: no interval, no verdict
RESAMPLES = 10_000
BOOTSTRAP_SEED = 0
CONFIDENCE = 0.95
# rad: a desired position this close to a joint limit is "at the stop"; the env clips in
# float32 (1e-7 rad off the float64 limit), a command pushed past the limit sits on it exactly
JOINT_STOP_TOLERANCE = 1e-3


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


def mean_std(values: Sequence[float]) -> tuple[float, float]:
    """Mean and (population) standard deviation of the finite values; the std is NaN for
    fewer than :data:`MIN_SEEDS` values (the spread of one seed is not 0 but unknown; the
    report shows a spread, like an interval, from 3 seeds on), both NaN for none."""
    a = finite(values)
    if a.size == 0:
        return float("nan"), float("nan")
    return float(a.mean()), float(a.std()) if a.size >= MIN_SEEDS else float("nan")


def finite(values: Sequence[float] | None) -> np.ndarray:
    """The finite values, as a flat float array (empty for None)."""
    a = np.asarray([] if values is None else values, dtype=float).ravel()
    return a[np.isfinite(a)]


def seeds_with_data(values: Sequence[float] | None) -> int:
    return int(finite(values).size)


def enough_seeds(*groups: Sequence[float] | None) -> bool:
    """Whether every group has at least :data:`MIN_SEEDS` finite per-seed values."""
    return all(seeds_with_data(group) >= MIN_SEEDS for group in groups)


@dataclass
class Interval:
    estimate: float
    low: float
    high: float

    def __str__(self) -> str:
        return f"{self.estimate:.3g} [{self.low:.3g}, {self.high:.3g}]"


STATISTICS: dict[str, Callable[..., Any]] = {"mean": np.mean, "median": np.median}


def _statistic(name: str) -> Callable[..., Any]:
    if name not in STATISTICS:
        raise ValueError(f"statistic must be one of {sorted(STATISTICS)}, got {name!r}")
    return STATISTICS[name]


def _percentiles(samples: np.ndarray, confidence: float) -> tuple[float, float]:
    tail = 100 * (1 - confidence) / 2
    low, high = np.percentile(samples, [tail, 100 - tail])
    return float(low), float(high)


def bootstrap(
    values: Sequence[float],
    statistic: str = "median",
    resamples: int = RESAMPLES,
    confidence: float = CONFIDENCE,
    seed: int = BOOTSTRAP_SEED,
) -> Interval | None:
    """The ``statistic`` (``"median"`` or ``"mean"``) of the finite per-seed values with a
    percentile bootstrap CI over seeds; None for no values."""
    f = _statistic(statistic)
    a = finite(values)
    if a.size == 0:
        return None
    rng = np.random.default_rng(seed)
    samples = f(a[rng.integers(0, a.size, (resamples, a.size))], axis=1)
    return Interval(float(f(a)), *_percentiles(samples, confidence))


def bootstrap_ratio(
    numerator: Sequence[float],
    denominator: Sequence[float],
    resamples: int = RESAMPLES,
    confidence: float = CONFIDENCE,
    seed: int = BOOTSTRAP_SEED,
    paired: bool = False,
    statistic: str = "mean",
) -> Interval | None:
    """``statistic(numerator) / statistic(denominator)`` (``"mean"`` or ``"median"`` over
    seeds) with a percentile bootstrap CI over seeds.

    ``paired``: the two are the same seeds measured twice (one policy in two simulators, one
    run at two times); one draw of seed indices is applied to both, and pairs with a
    non-finite member are dropped. Otherwise each group is resampled on its own. None when it
    is undefined: a group is empty, or the denominator's statistic (or any resampled one) is
    not positive (a ratio of returns is only meaningful for positive returns)."""
    f = _statistic(statistic)
    a = np.asarray(numerator, dtype=float).ravel()
    b = np.asarray(denominator, dtype=float).ravel()
    if paired:
        if a.shape != b.shape:
            raise ValueError(f"paired values need one pair per seed, got {a.size} and {b.size}")
        keep = np.isfinite(a) & np.isfinite(b)
        a, b = a[keep], b[keep]
    else:
        a, b = finite(a), finite(b)
    if a.size == 0 or b.size == 0 or f(b) <= 0:
        return None
    rng = np.random.default_rng(seed)
    index_a = rng.integers(0, a.size, (resamples, a.size))
    index_b = index_a if paired else rng.integers(0, b.size, (resamples, b.size))
    stat_a, stat_b = f(a[index_a], axis=1), f(b[index_b], axis=1)
    if np.any(stat_b <= 0):
        return None
    return Interval(float(f(a) / f(b)), *_percentiles(stat_a / stat_b, confidence))


def bootstrap_difference(
    first: Sequence[float],
    second: Sequence[float],
    resamples: int = RESAMPLES,
    confidence: float = CONFIDENCE,
    seed: int = BOOTSTRAP_SEED,
) -> Interval | None:
    """``mean(first) - mean(second)`` with a percentile bootstrap CI over seeds (each group
    resampled on its own: different variants' seeds are independent runs)."""
    a, b = finite(first), finite(second)
    if a.size == 0 or b.size == 0:
        return None
    rng = np.random.default_rng(seed)
    diff = a[rng.integers(0, a.size, (resamples, a.size))].mean(axis=1) - b[
        rng.integers(0, b.size, (resamples, b.size))
    ].mean(axis=1)
    return Interval(float(a.mean() - b.mean()), *_percentiles(diff, confidence))


# -- verdicts: (verdict, explanation) -----------------------------------------------------------
Verdict = tuple[str, str]
Groups = Mapping[str, Sequence[float] | None]


def too_few_seeds(groups: Groups) -> Verdict | None:
    """ "Not tested" when a group (a variant's per-seed values; None: not run) has fewer than
    :data:`MIN_SEEDS` finite values, with every group's count; None when all have enough."""
    counts = {name: seeds_with_data(values) for name, values in groups.items()}
    if groups and all(count >= MIN_SEEDS for count in counts.values()):
        return None
    parts = [
        f"{name} not run" if groups[name] is None else f"{name} {count}"
        for name, count in counts.items()
    ]
    return NOT_TESTED, (
        f"needs at least {MIN_SEEDS} seeds with data for each of "
        f"{', '.join(counts) or 'the variants'}; seeds here: {', '.join(parts) or 'none'}"
    )


def verdict_reward_ratio(
    cpg: Sequence[float] | None, cho: Sequence[float] | None, target: float = 6.0
) -> Verdict:
    """ "About 6x the reward of Cho et al. (warm)": the ratio of mean final returns over seeds
    (unpaired bootstrap) is within a factor 2 of ``target`` and its 95% CI lies above 1."""
    missing = too_few_seeds({"cpg-actor": cpg, "cho2019-warm": cho})
    if missing:
        return missing
    ratio = bootstrap_ratio(cpg, cho)
    if ratio is None:
        return NOT_SUPPORTED, "ratio undefined (Cho et al. (warm) return not positive)"
    ok = target / 2 <= ratio.estimate <= target * 2 and ratio.low > 1
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        f"ratio of means {ratio} (supported if within [{target / 2:g}, {target * 2:g}] and CI "
        "above 1)",
    )


def _differences_above_zero(first: Sequence[float], others: Groups) -> tuple[bool, list[str]]:
    """Whether the 95% CI of ``mean(first) - mean(other)`` lies above 0 for every other,
    and a ``"vs NAME: ..."`` part per other."""
    parts, ok = [], True
    for name, values in others.items():
        diff = bootstrap_difference(first, values)
        ok &= diff is not None and diff.low > 0
        parts.append(f"vs {name}: {diff}" if diff is not None else f"vs {name}: no data")
    return ok, parts


def verdict_better(open_loop: Sequence[float] | None, cho: Groups) -> Verdict:
    """ "Open-loop CPG-Actor beats Cho et al.": the 95% CI of the difference of mean final
    returns lies above 0 for every Cho et al. variant that ran (``cho``: variant -> per-seed
    final returns)."""
    if not cho:
        return NOT_TESTED, "needs cpg-actor-open-loop and cho2019-warm, cho2019 or cho2019-paper"
    missing = too_few_seeds({"cpg-actor-open-loop": open_loop, **cho})
    if missing:
        return missing
    ok, parts = _differences_above_zero(open_loop, cho)
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        "difference of mean final returns " + "; ".join(parts) + " (supported if CI above 0)",
    )


def ratio_of_medians(larger: Sequence[float], smaller: Sequence[float]) -> Interval | None:
    """``median(larger) / median(smaller)`` over seeds with an unpaired bootstrap CI, for a
    claim that ``larger`` is many times ``smaller``. Resampled as ``smaller / larger`` and
    inverted (a percentile interval inverts with it), so that a ``smaller`` of 0 (perfectly
    flat) gives an infinite ratio rather than none; None when ``larger``'s median, or a
    resampled one, is not positive (then the claim cannot hold)."""
    inverse = bootstrap_ratio(smaller, larger, statistic="median")
    if inverse is None:
        return None
    with np.errstate(divide="ignore"):
        low, high, estimate = np.divide(1.0, [inverse.high, inverse.low, inverse.estimate])
    return Interval(float(estimate), float(low), float(high))


def verdict_smooth(
    cpg: Sequence[float] | None, mlp: Sequence[float] | None, factor: float = 10.0
) -> Verdict:
    """ "CPG outputs are smooth where the MLP is bang-bang": the ratio of the per-seed
    smoothness medians, MLP / CPG-Actor (:func:`ratio_of_medians`; unpaired: the two agents'
    seeds are independent runs, seed k of one has nothing to do with seed k of the other), has
    a 95% CI whose lower bound is at least ``factor``. Medians, as one rough seed can carry a
    mean."""
    missing = too_few_seeds({"cpg-actor": cpg, "mlp": mlp})
    if missing:
        return missing
    ratio = ratio_of_medians(mlp, cpg)
    cpg_median, mlp_median = np.median(finite(cpg)), np.median(finite(mlp))
    medians = (
        f"median squared 2nd difference {cpg_median:.3g} (CPG-Actor) vs {mlp_median:.3g} rad^2 "
        "(MLP)"
    )
    if ratio is None:
        return NOT_SUPPORTED, f"{medians}; the MLP's median is 0 on resampled seeds: not bang-bang"
    ok = ratio.low >= factor
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        f"{medians}; ratio of medians MLP / CPG-Actor {ratio} (supported if the CI's lower "
        f"bound >= {factor:g})",
    )


def verdict_near_limits(
    p99: Sequence[float] | None,
    share: Sequence[float] | None = None,
    limit: float = VELOCITY_LIMIT,
    band: tuple[float, float] = (0.6, 1.2),
) -> Verdict:
    """ "Desired velocities stay near the motor limits": the median over seeds of the per-seed
    99th percentile of |desired velocity| has a 95% CI inside ``band`` x the limit (the range
    is used, and only just exceeded if at all). ``share``: per-seed shares within the limit,
    reported only."""
    missing = too_few_seeds({"cpg-actor": p99})
    if missing:
        return missing
    median = bootstrap(p99, "median")
    low, high = band[0] * limit, band[1] * limit
    ok = low <= median.low and median.high <= high
    within = finite(share)
    within_text = (
        f", median {100 * np.median(within):.1f}% within +-{limit:g} rad/s" if within.size else ""
    )
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        f"p99 |v| median over seeds {median} rad/s{within_text}; supported if the CI lies in "
        f"[{low:g}, {high:g}]",
    )


def verdict_hop_doubles(
    final: Sequence[float] | None,
    early: Sequence[float] | None,
    early_step: float,
    total_steps: float,
    threshold: float = 1.5,
) -> Verdict:
    """ "The hop height about doubles with training" (paper: 1M -> 60M steps): the CPG-Actor's
    mean hop height in the deterministic evaluations at the end over that at ``early_step``
    (1M), per seed ``final[i]`` and ``early[i]`` of the same run, is >= ``threshold`` and the
    95% CI of the ratio of means lies above 1. The bootstrap is paired: the same seeds are
    measured at two times, so one draw of seed indices serves both. Judged only on runs of at
    least twice ``early_step``: the hop height of an untrained agent is no baseline."""
    if total_steps < 2 * early_step:
        return NOT_TESTED, (
            f"needs runs of at least {2 * early_step:,.0f} steps (the paper compares "
            f"{early_step:,.0f} steps with the end); this run: {total_steps:,.0f}"
        )
    if final is None or early is None:
        return NOT_TESTED, "needs cpg-actor"
    a, b = np.asarray(final, dtype=float), np.asarray(early, dtype=float)
    pairs = int(np.sum(np.isfinite(a) & np.isfinite(b))) if a.shape == b.shape else 0
    if pairs < MIN_SEEDS:
        return NOT_TESTED, (
            f"needs at least {MIN_SEEDS} cpg-actor seeds with hop heights logged at "
            f"{early_step:,.0f} steps and at the end; seeds here: {pairs}"
        )
    ratio = bootstrap_ratio(a, b, paired=True)
    if ratio is None:
        return NOT_TESTED, f"ratio undefined (hop height at {early_step:,.0f} steps not positive)"
    ok = ratio.estimate >= threshold and ratio.low > 1
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        f"hop height at the end / at {early_step:,.0f} steps, ratio of means over {pairs} "
        f"seeds, paired: x{ratio} (supported if >= x{threshold:g} and CI above 1)",
    )


def verdict_best_during_training(cpg: Sequence[float] | None, others: Groups) -> Verdict:
    """ "The CPG-Actor performs best during training": the mean evaluation return over the
    whole run (the area under the curve, per seed) is above every other variant's, the 95% CI
    of each difference of means above 0 (``others``: variant -> per-seed values)."""
    if not others:
        return NOT_TESTED, "needs cpg-actor and another variant with evaluation curves"
    missing = too_few_seeds({"cpg-actor": cpg, **others})
    if missing:
        return missing
    ok, parts = _differences_above_zero(cpg, others)
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        "mean eval return over the run, difference of means " + "; ".join(parts)
        + " (supported if every CI is above 0)",
    )  # fmt: skip


def verdict_more_robust(
    first: Sequence[float] | None,
    second: Sequence[float] | None,
    names: tuple[str, str] = ("cpg-actor", "mlp"),
) -> Verdict:
    """ "``names[0]`` is more robust than ``names[1]``" under one perturbation: per seed, the
    return retained under it (:mod:`cpg_actor.robustness`; the mean over its levels of the
    return / the nominal return); supported if the 95% CI of the difference of the means over
    seeds (unpaired bootstrap: the two are independent runs) lies above 0."""
    missing = too_few_seeds({names[0]: first, names[1]: second})
    if missing:
        return missing
    diff = bootstrap_difference(first, second)
    ok = diff is not None and diff.low > 0
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        f"mean retention over the levels {np.mean(finite(first)):.3g} ({names[0]}) vs "
        f"{np.mean(finite(second)):.3g} ({names[1]}), difference of means {diff} (supported if "
        "the CI is above 0)",
    )


CPG_SIGNALS = ("theta_dot", "r_ddot")


def verdict_cho_flat(
    cpg: Mapping[str, Sequence[float]] | None,
    cho: Mapping[str, Mapping[str, Sequence[float]]],
    factor: float = 3.0,
) -> Verdict:
    """ "Cho et al.'s theta_dot and r_ddot stay almost flat (not responsive to the
    environment) where the CPG-Actor's are reshaped by feedback" (paper section V): for both
    signals and every Cho variant, the ratio of per-seed :func:`variability` medians,
    CPG-Actor / Cho (:func:`ratio_of_medians`, unpaired), has a 95% CI whose lower bound is at
    least ``factor`` (infinite for a Cho signal that is exactly flat). ``cpg`` and each
    ``cho[variant]`` map ``theta_dot`` and ``r_ddot`` to per-seed values."""
    if not cho:
        return NOT_TESTED, "needs cpg-actor and a Cho et al. variant with CPG traces"
    groups: dict[str, Sequence[float] | None] = {}
    for name in CPG_SIGNALS:
        groups[f"cpg-actor {name}"] = None if cpg is None else cpg[name]
        for variant, values in cho.items():
            groups[f"{variant} {name}"] = values[name]
    missing = too_few_seeds(groups)
    if missing:
        return missing
    ok, parts = True, []
    for variant, values in cho.items():
        for name in CPG_SIGNALS:
            ratio = ratio_of_medians(cpg[name], values[name])
            ok &= ratio is not None and ratio.low >= factor
            text = ratio if ratio else "undefined (the CPG-Actor's median is 0 on resampled seeds)"
            parts.append(f"{name} CPG-Actor / {variant}: {text}")
    cpg_text = ", ".join(f"{name} {np.median(finite(cpg[name])):.3g}" for name in CPG_SIGNALS)
    return (
        SUPPORTED if ok else NOT_SUPPORTED,
        f"median std over an episode: CPG-Actor {cpg_text} (rad/s, rad/s^2); ratio of medians "
        + "; ".join(parts)
        + f" (supported if every CI's lower bound >= {factor:g})",
    )


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
