"""The tests behind a verdict (Welch, paired, one-sample, band), Holm's correction of a
family, and the minimum effect a difference must reach.

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
  (``mean(first) - factor * mean(second)``), so the factor is their minimum effect.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cpg_actor.statistics.intervals import finite

ALPHA = 0.05  # the family-wise error rate of a report's verdicts (Holm)
WELCH = "Welch's t-test"
PAIRED = "paired t-test"
BAND = "one-sided one-sample t-tests"
HOLM = "Holm"


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
