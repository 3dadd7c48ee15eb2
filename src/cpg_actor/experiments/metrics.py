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

Verdicts (:func:`decide`): the bootstrap intervals are shown, the verdicts rest on tests.

* **the test**: Welch's t-test (:func:`welch_test`, two-sided, unequal variances) between
  variants, whose seeds are independent runs (seed k of one agent draws other numbers than seed
  k of another; they share only the packaged start gait, which every seed has alike). Not an
  exact permutation test: with 5 seeds a side its smallest two-sided p is 2/252 = 0.0079, so a
  Holm correction over 7 comparisons at 0.05 (smallest threshold 0.05/7 = 0.0071) could never
  reject, whatever the data. Welch's p can, at the price of assuming the per-seed means roughly
  normal. A **paired t-test** (:func:`paired_t_test`) where the same runs are measured twice
  (a run's hop height at 1M steps and at the end); not an exact sign-flip test, whose smallest
  two-sided p with 5 pairs is 2/32 = 0.0625. A band claim about one variant (the desired
  velocities near the motor limit) is two one-sided one-sample t-tests (:func:`band_test`),
  and variants against one fixed number (the open-loop grid floor) one-sample t-tests
  (:func:`one_sample_t_test`);
* **the family**: every test behind one set of verdicts (the reproduction report's claims; a
  robustness suite's claims over all its perturbations; the table of comparisons beyond the
  paper; the variants against the floor) is one family; their p-values are corrected together
  with Holm's step-down method (:func:`holm`) to a family-wise error rate of ``ALPHA``. A
  claim that needs several tests to pass (better than every Cho et al. variant) counts each;
* **the minimum effect** (:data:`MINIMUM_EFFECT`, per metric): a test must also find a
  difference of at least 5 % of the baseline's mean for returns (final, over the run) and hop
  heights, 0.05 for the return retained under a perturbation (a share of the nominal return),
  in the claimed direction; claims of a ratio test against the ratio itself
  (``mean(first) - factor * mean(second)``), so the factor is their minimum effect;
* **supported**: every test of the claim passes (Holm-adjusted p < ``ALPHA``, difference in
  the claimed direction and at least the minimum effect) and the claim's other conditions
  hold; the verdict's text names the test, the family size and the correction.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
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
ALPHA = 0.05  # the family-wise error rate of a report's verdicts (Holm)


@dataclass(frozen=True)
class MinimumEffect:
    """The smallest difference a "supported" needs: ``relative`` x |the baseline's mean| or
    ``absolute`` (in the metric's units), whichever is larger."""

    relative: float = 0.0
    absolute: float = 0.0

    def threshold(self, baseline_mean: float) -> float:
        return max(self.absolute, self.relative * abs(baseline_mean))

    def __str__(self) -> str:
        parts = [f"{100 * self.relative:g}% of the baseline"] if self.relative else []
        parts += [f"{self.absolute:g}"] if self.absolute or not parts else []
        return " or ".join(parts)


# per metric: a difference smaller than this is no evidence of "better", however small its p
MINIMUM_EFFECT = {
    "return": MinimumEffect(relative=0.05),  # final return, eval return over the run
    "hop_height": MinimumEffect(relative=0.05),
    # the return retained under a perturbation (a share of the nominal return): 5 points
    "retention": MinimumEffect(absolute=0.05),
}


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


def three_figures(value: float) -> str:
    """Three significant figures, without an exponent for 1,000 to 99,999 (a return reads
    1083, not 1.08e+03)."""
    return f"{value:.0f}" if 1e3 <= abs(value) < 1e5 else f"{value:.3g}"


@dataclass
class Interval:
    estimate: float
    low: float
    high: float

    def __str__(self) -> str:
        low, high = three_figures(self.low), three_figures(self.high)
        return f"{three_figures(self.estimate)} [{low}, {high}]"


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


# -- tests and the family's correction ----------------------------------------------------------
WELCH = "Welch's t-test"
PAIRED = "paired t-test"
BAND = "one-sided one-sample t-tests"
HOLM = "Holm"
Verdict = tuple[str, str]  # (verdict, explanation)


def _t_tail(t: float, df: float) -> float:
    """P(T > t) for Student's t with ``df`` degrees of freedom (scipy)."""
    from scipy import stats

    return float(stats.t.sf(t, df))


def _two_sided(difference: float, variance: float, df: float) -> float:
    """Two-sided p of ``difference`` with the squared standard error ``variance``; without any
    spread the difference is exact: p 0 if it is not 0, else 1."""
    if variance == 0:
        return 0.0 if difference != 0 else 1.0
    return min(1.0, 2.0 * _t_tail(abs(difference) / math.sqrt(variance), df))


def _two_or_more(*groups: np.ndarray) -> None:
    if any(group.size < 2 for group in groups):
        raise ValueError(f"a t-test needs 2 or more values a side, got {[g.size for g in groups]}")


def welch_test(
    first: Sequence[float], second: Sequence[float], scale: float = 1.0
) -> tuple[float, float]:
    """Welch's t-test (unequal variances, Welch-Satterthwaite degrees of freedom) of
    ``mean(first) = scale * mean(second)`` over the finite per-seed values: the difference
    ``mean(first) - scale * mean(second)`` and its two-sided p. ``scale`` tests a ratio of
    means (the second group's values are scaled, and its variance with them)."""
    a, b = finite(first), scale * finite(second)
    _two_or_more(a, b)
    var_a, var_b = a.var(ddof=1) / a.size, b.var(ddof=1) / b.size
    variance = var_a + var_b
    df = variance**2 / (var_a**2 / (a.size - 1) + var_b**2 / (b.size - 1)) if variance else 1.0
    difference = float(a.mean() - b.mean())
    return difference, _two_sided(difference, variance, df)


def paired_t_test(first: Sequence[float], second: Sequence[float]) -> tuple[float, float]:
    """The paired t-test of ``first[i] - second[i]`` (the same runs measured twice; pairs with
    a non-finite member left out): the mean difference and its two-sided p."""
    a, b = np.asarray(first, dtype=float).ravel(), np.asarray(second, dtype=float).ravel()
    if a.shape != b.shape:
        raise ValueError(f"paired values need one pair per seed, got {a.size} and {b.size}")
    d = (a - b)[np.isfinite(a) & np.isfinite(b)]
    _two_or_more(d)
    difference = float(d.mean())
    return difference, _two_sided(difference, d.var(ddof=1) / d.size, d.size - 1)


def one_sample_t_test(values: Sequence[float], value: float) -> tuple[float, float]:
    """The one-sample t-test of ``mean(values) = value`` over the finite values (a variant
    against one fixed number, e.g. the open-loop grid floor): ``mean - value`` and its
    two-sided p."""
    a = finite(values)
    _two_or_more(a)
    difference = float(a.mean() - value)
    return difference, _two_sided(difference, a.var(ddof=1) / a.size, a.size - 1)


def band_test(values: Sequence[float], low: float, high: float) -> tuple[float, float]:
    """Whether the mean of the finite ``values`` lies inside ``[low, high]``: two one-sided
    one-sample t-tests (mean > low, mean < high), both needed, so the p is the larger of the
    two. Returns the distance of the mean to the nearer bound (negative outside) and that p."""
    a = finite(values)
    _two_or_more(a)
    mean, variance = float(a.mean()), a.var(ddof=1) / a.size
    ps = []
    for distance in (mean - low, high - mean):
        if variance == 0:
            ps.append(0.0 if distance > 0 else 1.0)
        else:
            ps.append(_t_tail(distance / math.sqrt(variance), a.size - 1))
    return min(mean - low, high - mean), max(ps)


def holm(pvalues: Sequence[float]) -> list[float]:
    """Holm's step-down adjusted p-values of a family (in the given order): the i-th smallest p
    times (family size - i + 1), never below an earlier one, at most 1. Rejecting where the
    adjusted p < alpha keeps the family-wise error rate at alpha."""
    p = np.asarray(pvalues, dtype=float)
    adjusted = np.empty_like(p)
    running = 0.0
    for rank, index in enumerate(np.argsort(p, kind="stable")):
        running = max(running, min(1.0, (p.size - rank) * p[index]))
        adjusted[index] = running
    return [float(x) for x in adjusted]


@dataclass
class Test:
    """One test behind a claim, oriented so that a positive ``difference`` is the claimed
    direction: ``name`` (which test), ``label`` (what it compares), ``difference`` (the
    estimate tested against 0), ``p`` (its p-value), ``minimum`` (the smallest difference
    that counts, :data:`MINIMUM_EFFECT`) and ``adjusted`` (its Holm-adjusted p, set by
    :func:`decide`)."""

    name: str
    label: str
    difference: float
    p: float
    minimum: float = 0.0
    adjusted: float = math.nan

    def passed(self, alpha: float = ALPHA) -> bool:
        return self.adjusted < alpha and self.difference > 0 and self.difference >= self.minimum

    def __str__(self) -> str:
        minimum = f" (minimum {self.minimum:.3g})" if self.minimum else ""
        return (f"{self.label} {self.difference:+.3g}{minimum}, p = {self.p:.2g}, "
                f"{HOLM} p = {self.adjusted:.2g}")  # fmt: skip


def better_test(first: Sequence[float], second: Sequence[float], metric: str, label: str) -> Test:
    """``first`` better (higher) than ``second`` in ``metric`` (a key of
    :data:`MINIMUM_EFFECT`): Welch's t-test, the minimum effect taken of ``second``'s mean."""
    difference, p = welch_test(first, second)
    minimum = MINIMUM_EFFECT[metric].threshold(float(np.mean(finite(second))))
    return Test(WELCH, label, difference, p, minimum)


def ratio_test(
    larger: Sequence[float], smaller: Sequence[float], factor: float, label: str
) -> Test:
    """``mean(larger) > factor * mean(smaller)``: Welch's t-test of their difference (the
    factor is the claim's minimum effect)."""
    return Test(WELCH, label, *welch_test(larger, smaller, scale=factor))


@dataclass
class Claim:
    """A claim's evidence before its family's correction: the ``tests`` that must all pass,
    ``condition`` (its other conditions hold), the text (``evidence``: estimates and bootstrap
    CIs, for display; ``rule``: what "supported" needs besides the tests); or a verdict
    ``fixed`` without tests (not tested, undefined)."""

    evidence: str
    tests: list[Test] = field(default_factory=list)
    condition: bool = True
    rule: str = ""
    fixed: str | None = None


def family_text(size: int, alpha: float = ALPHA) -> str:
    return f"{HOLM} correction over a family of {size} tests at alpha {alpha:g}"


def decide(claims: Sequence[Claim], alpha: float = ALPHA) -> list[Verdict]:
    """The verdicts of a report's claims, one family: the p-values of every test of every
    claim (those not ``fixed``) are Holm-corrected together; a claim is supported when each of
    its tests passes (:meth:`Test.passed`) and its ``condition`` holds. Each explanation names
    the tests, the family's size and the correction."""
    tests = [test for claim in claims if claim.fixed is None for test in claim.tests]
    for test, adjusted in zip(tests, holm([test.p for test in tests]), strict=True):
        test.adjusted = adjusted
    verdicts = []
    for claim in claims:
        if claim.fixed is not None:
            verdicts.append((claim.fixed, claim.evidence))
            continue
        ok = claim.condition and all(test.passed(alpha) for test in claim.tests)
        names = ", ".join(dict.fromkeys(test.name for test in claim.tests))
        rule = f"; {claim.rule}" if claim.rule else ""
        text = (
            f"{claim.evidence}; {names}: " + "; ".join(map(str, claim.tests))
            + f" ({family_text(len(tests), alpha)}; supported if every {HOLM} p < {alpha:g} "
            f"with the difference above 0 and its minimum{rule})"
        )  # fmt: skip
        verdicts.append((SUPPORTED if ok else NOT_SUPPORTED, text))
    return verdicts


# -- claims -------------------------------------------------------------------------------------
Groups = Mapping[str, Sequence[float] | None]


def too_few_seeds(groups: Groups) -> Claim | None:
    """ "Not tested" when a group (a variant's per-seed values; None: not run) has fewer than
    :data:`MIN_SEEDS` finite values, with every group's count; None when all have enough."""
    counts = {name: seeds_with_data(values) for name, values in groups.items()}
    if groups and all(count >= MIN_SEEDS for count in counts.values()):
        return None
    parts = [
        f"{name} not run" if groups[name] is None else f"{name} {count}"
        for name, count in counts.items()
    ]
    return Claim(
        f"needs at least {MIN_SEEDS} seeds with data for each of "
        f"{', '.join(counts) or 'the variants'}; seeds here: {', '.join(parts) or 'none'}",
        fixed=NOT_TESTED,
    )


def verdict_reward_ratio(
    cpg: Sequence[float] | None, cho: Sequence[float] | None, target: float = 6.0
) -> Claim:
    """ "About 6x the reward of Cho et al. (warm)": the ratio of mean final returns over seeds
    is within a factor 2 of ``target`` and the CPG-Actor's return is higher (Welch's t-test,
    :data:`MINIMUM_EFFECT` of returns); the ratio's unpaired bootstrap CI is shown."""
    missing = too_few_seeds({"cpg-actor": cpg, "cho2019-warm": cho})
    if missing:
        return missing
    ratio = bootstrap_ratio(cpg, cho)
    if ratio is None:
        return Claim("ratio undefined (Cho et al. (warm) return not positive)",
                     fixed=NOT_SUPPORTED)  # fmt: skip
    return Claim(
        f"ratio of means {ratio}",
        [better_test(cpg, cho, "return", "cpg-actor - cho2019-warm")],
        target / 2 <= ratio.estimate <= target * 2,
        f"the ratio of means within [{target / 2:g}, {target * 2:g}]",
    )


def verdict_better(open_loop: Sequence[float] | None, cho: Groups) -> Claim:
    """ "Open-loop CPG-Actor beats Cho et al.": its mean final return is higher than every Cho
    et al. variant's that ran (``cho``: variant -> per-seed final returns), by Welch's t-test
    and the minimum effect of returns."""
    if not cho:
        return Claim("needs cpg-actor-open-loop and cho2019-warm, cho2019 or cho2019-paper",
                     fixed=NOT_TESTED)  # fmt: skip
    missing = too_few_seeds({"cpg-actor-open-loop": open_loop, **cho})
    if missing:
        return missing
    parts = [
        f"vs {name}: {bootstrap_difference(open_loop, values)}" for name, values in cho.items()
    ]
    return Claim(
        "difference of mean final returns " + "; ".join(parts),
        [better_test(open_loop, values, "return", f"cpg-actor-open-loop - {name}")
         for name, values in cho.items()],
    )  # fmt: skip


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
) -> Claim:
    """ "CPG outputs are smooth where the MLP is bang-bang": the MLP's mean smoothness (squared
    second difference) is more than ``factor`` times the CPG-Actor's, by Welch's t-test of
    ``mean(mlp) - factor * mean(cpg)`` (unpaired: the two agents' seeds are independent runs).
    The medians over seeds and their ratio with its bootstrap CI (:func:`ratio_of_medians`)
    are shown, as one rough seed can carry a mean."""
    missing = too_few_seeds({"cpg-actor": cpg, "mlp": mlp})
    if missing:
        return missing
    ratio = ratio_of_medians(mlp, cpg)
    cpg_median, mlp_median = np.median(finite(cpg)), np.median(finite(mlp))
    ratio_text = ratio if ratio is not None else "undefined (the MLP's median is 0: flat)"
    return Claim(
        f"median squared 2nd difference {cpg_median:.3g} (CPG-Actor) vs {mlp_median:.3g} rad^2 "
        f"(MLP), ratio of medians MLP / CPG-Actor {ratio_text}",
        [ratio_test(mlp, cpg, factor, f"mean MLP - {factor:g} x mean CPG-Actor")],
    )


def verdict_near_limits(
    p99: Sequence[float] | None,
    share: Sequence[float] | None = None,
    limit: float = VELOCITY_LIMIT,
    band: tuple[float, float] = (0.6, 1.2),
) -> Claim:
    """ "Desired velocities stay near the motor limits": the mean over seeds of the per-seed
    99th percentile of |desired velocity| lies inside ``band`` x the limit (the range is
    used, and only just exceeded if at all), by two one-sided t-tests (:func:`band_test`).
    The median over seeds with its bootstrap CI is shown; ``share``: per-seed shares within
    the limit, shown only."""
    missing = too_few_seeds({"cpg-actor": p99})
    if missing:
        return missing
    median = bootstrap(p99, "median")
    low, high = band[0] * limit, band[1] * limit
    within = finite(share)
    within_text = (
        f", median {100 * np.median(within):.1f}% within +-{limit:g} rad/s" if within.size else ""
    )
    distance, p = band_test(p99, low, high)
    label = f"mean {np.mean(finite(p99)):.3g} rad/s inside [{low:g}, {high:g}], margin"
    return Claim(f"p99 |v| median over seeds {median} rad/s{within_text}",
                 [Test(BAND, label, distance, p)])  # fmt: skip


def verdict_hop_doubles(
    final: Sequence[float] | None,
    early: Sequence[float] | None,
    early_step: float,
    total_steps: float,
    threshold: float = 1.5,
) -> Claim:
    """ "The hop height about doubles with training" (paper: 1M -> 60M steps): the CPG-Actor's
    mean hop height in the deterministic evaluations at the end over that at ``early_step``
    (1M), per seed ``final[i]`` and ``early[i]`` of the same run, is >= ``threshold``, and the
    hop height rose (paired t-test: the same runs measured at two times; the minimum effect of
    hop heights). The ratio's paired bootstrap CI is shown. Judged only on runs of at least
    twice ``early_step``: the hop height of an untrained agent is no baseline."""
    if total_steps < 2 * early_step:
        return Claim(
            f"needs runs of at least {2 * early_step:,.0f} steps (the paper compares "
            f"{early_step:,.0f} steps with the end); this run: {total_steps:,.0f}",
            fixed=NOT_TESTED,
        )
    if final is None or early is None:
        return Claim("needs cpg-actor", fixed=NOT_TESTED)
    a, b = np.asarray(final, dtype=float), np.asarray(early, dtype=float)
    keep = np.isfinite(a) & np.isfinite(b) if a.shape == b.shape else np.zeros(0, bool)
    pairs = int(keep.sum())
    if pairs < MIN_SEEDS:
        return Claim(
            f"needs at least {MIN_SEEDS} cpg-actor seeds with hop heights logged at "
            f"{early_step:,.0f} steps and at the end; seeds here: {pairs}",
            fixed=NOT_TESTED,
        )
    ratio = bootstrap_ratio(a, b, paired=True)
    if ratio is None:
        return Claim(f"ratio undefined (hop height at {early_step:,.0f} steps not positive)",
                     fixed=NOT_TESTED)  # fmt: skip
    difference, p = paired_t_test(a, b)
    minimum = MINIMUM_EFFECT["hop_height"].threshold(float(b[keep].mean()))
    return Claim(
        f"hop height at the end / at {early_step:,.0f} steps, ratio of means over {pairs} "
        f"seeds, paired: x{ratio}",
        [Test(PAIRED, "end - early (m)", difference, p, minimum)],
        ratio.estimate >= threshold,
        f"the ratio of means >= x{threshold:g}",
    )


def verdict_best_during_training(cpg: Sequence[float] | None, others: Groups) -> Claim:
    """ "The CPG-Actor performs best during training": its mean evaluation return over the
    whole run (the area under the curve, per seed) is higher than every other variant's
    (``others``: variant -> per-seed values), each by Welch's t-test and the minimum effect of
    returns."""
    if not others:
        return Claim("needs cpg-actor and another variant with evaluation curves",
                     fixed=NOT_TESTED)  # fmt: skip
    missing = too_few_seeds({"cpg-actor": cpg, **others})
    if missing:
        return missing
    parts = [f"vs {name}: {bootstrap_difference(cpg, values)}" for name, values in others.items()]
    return Claim(
        "mean eval return over the run, difference of means " + "; ".join(parts),
        [better_test(cpg, values, "return", f"cpg-actor - {name}")
         for name, values in others.items()],
    )  # fmt: skip


def verdict_more_robust(
    first: Sequence[float] | None,
    second: Sequence[float] | None,
    names: tuple[str, str] = ("cpg-actor", "mlp"),
) -> Claim:
    """ "``names[0]`` is more robust than ``names[1]``" under one perturbation: per seed, the
    return retained under it (:mod:`cpg_actor.robustness`; the mean over its levels of the
    return / the nominal return); supported if its mean over seeds is higher by Welch's t-test
    (the two are independent runs) and by the minimum effect of retention."""
    missing = too_few_seeds({names[0]: first, names[1]: second})
    if missing:
        return missing
    return Claim(
        f"mean retention over the levels {np.mean(finite(first)):.3g} ({names[0]}) vs "
        f"{np.mean(finite(second)):.3g} ({names[1]}), difference of means "
        f"{bootstrap_difference(first, second)}",
        [better_test(first, second, "retention", f"{names[0]} - {names[1]}")],
    )


CPG_SIGNALS = ("theta_dot", "r_ddot")


def verdict_cho_flat(
    cpg: Mapping[str, Sequence[float]] | None,
    cho: Mapping[str, Mapping[str, Sequence[float]]],
    factor: float = 3.0,
) -> Claim:
    """ "Cho et al.'s theta_dot and r_ddot stay almost flat (not responsive to the
    environment) where the CPG-Actor's are reshaped by feedback" (paper section V): for both
    signals and every Cho variant, the CPG-Actor's mean per-seed :func:`variability` is more
    than ``factor`` times Cho's (Welch's t-test of ``mean(cpg) - factor * mean(cho)``,
    unpaired). The ratio of medians with its bootstrap CI (:func:`ratio_of_medians`) is shown.
    ``cpg`` and each ``cho[variant]`` map ``theta_dot`` and ``r_ddot`` to per-seed values."""
    if not cho:
        return Claim("needs cpg-actor and a Cho et al. variant with CPG traces", fixed=NOT_TESTED)
    groups: dict[str, Sequence[float] | None] = {}
    for name in CPG_SIGNALS:
        groups[f"cpg-actor {name}"] = None if cpg is None else cpg[name]
        for variant, values in cho.items():
            groups[f"{variant} {name}"] = values[name]
    missing = too_few_seeds(groups)
    if missing:
        return missing
    parts, tests = [], []
    for variant, values in cho.items():
        for name in CPG_SIGNALS:
            ratio = ratio_of_medians(cpg[name], values[name])
            text = ratio if ratio else "undefined (the CPG-Actor's median is 0 on resampled seeds)"
            parts.append(f"{name} CPG-Actor / {variant}: {text}")
            label = f"{name} mean CPG-Actor - {factor:g} x mean {variant}"
            tests.append(ratio_test(cpg[name], values[name], factor, label))
    cpg_text = ", ".join(f"{name} {np.median(finite(cpg[name])):.3g}" for name in CPG_SIGNALS)
    return Claim(
        f"median std over an episode: CPG-Actor {cpg_text} (rad/s, rad/s^2); ratio of medians "
        + "; ".join(parts),
        tests,
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
