"""Bootstrap intervals over seeds (cpg_actor.statistics.intervals) on constructed data."""

import numpy as np
import pytest

from cpg_actor import statistics as st


def test_bootstrap_ratio_and_difference():
    exact = st.bootstrap_ratio([6.0, 6.0, 6.0], [1.0, 1.0, 1.0])
    assert (exact.estimate, exact.low, exact.high) == pytest.approx((6.0, 6.0, 6.0))
    rng = np.random.default_rng(1)
    a = 60 + rng.normal(0, 5, 5)
    b = 10 + rng.normal(0, 1, 5)
    ratio = st.bootstrap_ratio(a, b)
    assert ratio.estimate == pytest.approx(a.mean() / b.mean())
    assert ratio.low < ratio.estimate < ratio.high
    assert 4 < ratio.low and ratio.high < 8
    # wider with fewer seeds
    narrow = st.bootstrap_ratio(a, b)
    wide = st.bootstrap_ratio(a[:2], b[:2])
    assert wide.high - wide.low > 0 and narrow is not None
    assert st.bootstrap_ratio(a, [-1.0, -2.0]) is None  # ratio undefined for negative returns
    assert st.bootstrap_ratio(a, [-1.0, 5.0]) is None  # a resampled mean can be negative
    assert st.bootstrap_ratio([], b) is None
    diff = st.bootstrap_difference(a, b)
    assert diff.estimate == pytest.approx(a.mean() - b.mean())
    assert diff.low > 0
    same = st.bootstrap_difference(b, b + rng.normal(0, 1, 5))
    assert same.low < 0 < same.high


def test_bootstrap_is_deterministic_with_the_documented_resamples():
    values = [4.3e-4, 7.4e-4, 4.9e-3, 6.9e-3, 6.1e-4]
    first, second = st.bootstrap(values), st.bootstrap(values)
    assert (first.estimate, first.low, first.high) == (second.estimate, second.low, second.high)
    assert first.estimate == pytest.approx(7.4e-4)  # the median of the seeds
    assert first.low <= 6.1e-4 and first.high >= 4.9e-3
    assert st.RESAMPLES == 10_000 and st.BOOTSTRAP_SEED == 0
    assert st.bootstrap([]) is None
    assert st.bootstrap([1.0, 2.0, 6.0], "mean").estimate == pytest.approx(3.0)
    with pytest.raises(ValueError, match="statistic"):
        st.bootstrap([1.0], "mode")


def test_the_paired_bootstrap_resamples_seed_indices_once_for_both():
    early = [0.05, 0.1, 0.2, 0.4, 0.8]  # seeds differ a lot, each exactly doubles
    final = [2 * x for x in early]
    paired = st.bootstrap_ratio(final, early, paired=True)
    assert (paired.estimate, paired.low, paired.high) == pytest.approx((2.0, 2.0, 2.0))
    unpaired = st.bootstrap_ratio(final, early)
    assert unpaired.low < 1.0 < unpaired.high  # the seeds' spread, not the change
    # so does the t-test of the same runs: pairs remove the seeds' spread
    assert st.paired_t_test(final, early)[1] < st.welch_test(final, early)[1] / 4
    with pytest.raises(ValueError, match="one pair per seed"):
        st.bootstrap_ratio([1.0, 2.0], [1.0], paired=True)


def test_numbers_in_tables_read_without_an_exponent_below_100000():
    assert st.three_figures(1083.4) == "1083"
    assert st.three_figures(-12345.6) == "-12346"
    assert st.three_figures(0.000172) == "0.000172"
    assert st.three_figures(926.2) == "926"
    assert st.three_figures(2.5e5) == "2.5e+05"
    assert str(st.Interval(1083.4, 1070.2, 1090.0)) == "1083 [1070, 1090]"
