"""Bootstrap confidence intervals over seeds, and the per-seed bookkeeping they rest on.

* **per seed, then over seeds**: each number is one value per run (seed); a variant's
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

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

MIN_SEEDS = 3  # fewer seeds on a side: no interval, no verdict
RESAMPLES = 10_000
BOOTSTRAP_SEED = 0
CONFIDENCE = 0.95


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
