"""The tests behind the verdicts: Welch's t-test, the paired t-test and the band test against
scipy's reference implementations, Holm's correction, the minimum effect, and families in
which the correction or the minimum effect turns a raw "supported" into "not supported"."""

import pytest
from scipy import stats

from cpg_actor import statistics as st
from cpg_actor.robustness.summary import markdown, verdicts
from cpg_actor.robustness.verdicts import verdict_more_robust
from cpg_actor_studies.hopper_paper import claims as paper

FIRST = [0.82, 0.91, 0.77, 0.95, 0.88]
SECOND = [0.61, 0.72, 0.70, 0.55, 0.81, 0.66]


def test_welch_and_paired_p_values_match_scipy():
    difference, p = st.welch_test(FIRST, SECOND)
    reference = stats.ttest_ind(FIRST, SECOND, equal_var=False)
    assert difference == pytest.approx(sum(FIRST) / 5 - sum(SECOND) / 6)
    assert p == pytest.approx(reference.pvalue, rel=1e-9)
    # a ratio: mean(first) = 1.2 x mean(second), the second's values (and variance) scaled
    _, p = st.welch_test(FIRST, SECOND, scale=1.2)
    scaled = [1.2 * x for x in SECOND]
    assert p == pytest.approx(stats.ttest_ind(FIRST, scaled, equal_var=False).pvalue, rel=1e-9)
    # NaN seeds (no data) are left out
    _, p_nan = st.welch_test([*FIRST, float("nan")], SECOND)
    assert p_nan == pytest.approx(reference.pvalue, rel=1e-9)
    difference, p = st.paired_t_test(FIRST, SECOND[:5])
    assert p == pytest.approx(stats.ttest_rel(FIRST, SECOND[:5]).pvalue, rel=1e-9)
    # a published value: Student's sleep data (paired), t = 4.06, df = 9, p = 0.00283
    drug_1 = [0.7, -1.6, -0.2, -1.2, -0.1, 3.4, 3.7, 0.8, 0.0, 2.0]
    drug_2 = [1.9, 0.8, 1.1, 0.1, -0.1, 4.4, 5.5, 1.6, 4.6, 3.4]
    difference, p = st.paired_t_test(drug_2, drug_1)
    assert difference == pytest.approx(1.58) and p == pytest.approx(0.002833, rel=1e-3)
    with pytest.raises(ValueError, match="2 or more"):
        st.welch_test([1.0], SECOND)


def test_one_sample_t_test_matches_scipy():
    difference, p = st.one_sample_t_test(FIRST, 0.8)
    assert difference == pytest.approx(sum(FIRST) / 5 - 0.8)
    assert p == pytest.approx(stats.ttest_1samp(FIRST, 0.8).pvalue, rel=1e-9)
    assert st.one_sample_t_test([3.0, 3.0, 3.0], 2.0) == (1.0, 0.0)  # no spread: exact


def test_band_test_is_two_one_sided_tests():
    values = [14.0, 15.0, 16.0, 13.0, 14.5]
    margin, p = st.band_test(values, 9.0, 18.0)
    low = stats.ttest_1samp(values, 9.0, alternative="greater").pvalue
    high = stats.ttest_1samp(values, 18.0, alternative="less").pvalue
    assert margin == pytest.approx(18.0 - 14.5) and p == pytest.approx(max(low, high))
    assert st.band_test([20.0, 21.0, 22.0], 9.0, 18.0)[0] < 0  # outside: a negative margin


def test_holm_steps_down_and_stays_monotone():
    adjusted = st.holm([0.01, 0.04, 0.03, 0.005])
    # sorted 0.005 x 4, 0.01 x 3, 0.03 x 2, 0.04 x 1 -> kept from falling below 0.06
    assert adjusted == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert st.holm([0.5, 0.9]) == pytest.approx([1.0, 1.0])  # at most 1
    assert st.holm([]) == []


def _suite(shifts, seeds=5):
    """Robustness results: per perturbation the CPG-Actor's retention ``shift`` above the
    MLP's, the same spread of seeds on both sides."""
    spread = [0.0, 0.05, 0.10, 0.15, 0.20][:seeds]
    runs = []
    for variant, offset in (("cpg-actor", 1.0), ("mlp", 0.0)):
        for seed, noise in enumerate(spread):
            perturbations = {
                f"axis{i}": {"levels": [{"level": 1.0,
                                         "retention": 0.6 + noise + offset * shift}]}
                for i, shift in enumerate(shifts)
            }  # fmt: skip
            runs.append({"variant": variant, "seed": seed, "perturbations": perturbations})
    return runs, [f"axis{i}" for i in range(len(shifts))]


def test_a_raw_supported_that_does_not_survive_the_family():
    """A 0.14 lead (Welch p about 0.02) is supported alone, not in a family of 7 (Holm: the
    smallest p needs < 0.05 / 7); a 0.4 lead survives the same family."""
    runs, names = _suite([0.14])
    (row,) = verdicts(runs, names)
    assert row["verdict"] == st.SUPPORTED and 0.01 < row["p"] < 0.05
    runs, names = _suite([0.4] + [0.14] * 6)
    rows = verdicts(runs, names)
    assert [row["verdict"] for row in rows] == [st.SUPPORTED] + [st.NOT_SUPPORTED] * 6
    assert all(row["family"] == 7 and row["test"] == st.WELCH for row in rows)
    assert rows[1]["p"] < 0.05 < rows[1]["p_holm"]
    # the text names the test, the family's size and the correction
    assert "Welch's t-test" in rows[1]["why"]
    assert "Holm correction over a family of 7 tests" in rows[1]["why"]
    data = {"verdicts": rows, "variants": {}, "metrics": [], "robot": "hopper",
            "episodes": 4, "env_seed": 1000, "cycle": "hop"}  # fmt: skip
    assert "family of 7 tests" in markdown(data)


def test_a_difference_below_the_minimum_effect_is_not_supported():
    """Every episode falls on both sides: retention 0.006 apart, with no spread at all the
    test is certain (p 0), but 0.006 is below the minimum effect of retention (0.05)."""
    first, second = [0.106] * 5, [0.1] * 5
    verdict, why = st.decide([verdict_more_robust(first, second)])[0]
    assert verdict == st.NOT_SUPPORTED and "minimum 0.05" in why
    assert st.decide([verdict_more_robust([0.2] * 5, second)])[0][0] == st.SUPPORTED
    # returns: 5% of the baseline's mean
    close = st.better_test([1030.0, 1031.0, 1029.0], [1000.0, 1001.0, 999.0], "return", "a - b")
    assert close.minimum == pytest.approx(50.0) and close.p < 1e-3
    (claim_verdict, _), = st.decide([paper.verdict_best_during_training(
        [1030.0, 1031.0, 1029.0], {"mlp": [1000.0, 1001.0, 999.0]})])  # fmt: skip
    assert claim_verdict == st.NOT_SUPPORTED


def test_claims_of_a_report_are_one_family():
    """Claims decided together: each test's p is corrected over every claim's tests. Two
    claims each supported alone (p 0.038 and 0.048) are not supported together (Holm: the
    smaller p x 2 = 0.076); a strong claim in the same family stays supported."""
    cpg = [5.0, 6.0, 7.0, 6.5]
    first = paper.verdict_best_during_training(cpg, {"mlp": [4.3, 5.3, 4.8, 4.5]})
    second = paper.verdict_best_during_training(cpg, {"mlp-warm": [4.4, 5.4, 4.9, 4.6]})
    for claim in (first, second):
        verdict, why = st.decide([claim])[0]
        assert verdict == st.SUPPORTED and "family of 1 tests" in why
    strong = paper.verdict_better([600.0, 610.0, 620.0, 605.0], {"cho2019-warm": [400.0] * 4})
    decided = st.decide([first, second, strong])
    assert [v for v, _ in decided] == [st.NOT_SUPPORTED, st.NOT_SUPPORTED, st.SUPPORTED]
    assert first.tests[0].adjusted == pytest.approx(2 * first.tests[0].p)
    assert all("Holm correction over a family of 3 tests" in why for _, why in decided)
