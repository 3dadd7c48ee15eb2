"""The family of tests that the results folders' analyses share: the best variant against the
others, judged with Holm and a minimum effect, both ways."""

import math

import numpy as np
import pytest

from cpg_actor import statistics as st
from cpg_actor_studies import family as f

FIVE_PERCENT = lambda other: 0.05 * abs(float(np.mean(other)))  # noqa: E731


def test_the_best_mean_is_tested_against_each_other_variant():
    data = {"a": [10.0, 11.0, 9.0, 10.5, 9.5], "b": [20.0, 21.0, 19.0, 20.5, 19.5],
            "c": [15.0, 14.0, 16.0, 15.5, 14.5]}  # fmt: skip
    best, tests = f.best_against_others(data, "return", True, False, FIVE_PERCENT)
    assert best == "b"
    assert [t["label"] for t in tests] == ["b vs a", "b vs c"]
    assert tests[0]["difference"] == pytest.approx(10.0, rel=1e-9)
    assert tests[0]["minimum"] == pytest.approx(0.5, rel=1e-9)
    f.judge(tests)
    assert [t["verdict"] for t in tests] == ["yes", "yes"]


def test_lower_is_better_on_a_log_scale():
    data = {"rough": [4e-3, 5e-3, 6e-3, 5e-3], "smooth": [1e-4, 1.2e-4, 0.8e-4, 1e-4]}
    best, tests = f.best_against_others(data, "smoothness", False, True, lambda _: math.log(1.25))
    assert best == "smooth"
    (test,) = f.judge(tests)
    assert math.exp(test["difference"]) == pytest.approx(50.0, rel=0.05)  # the factor
    assert test["verdict"] == "yes"
    assert "x" in f.table(tests)[2]


def test_a_difference_below_its_minimum_does_not_count():
    rng = np.random.default_rng(0)
    data = {"a": list(100 + rng.normal(0, 0.1, 8)), "b": list(101 + rng.normal(0, 0.1, 8))}
    _, tests = f.best_against_others(data, "return", True, False, FIVE_PERCENT)
    (test,) = f.judge(tests)
    assert test["adjusted"] < 1e-6  # clearly different, but 1 % is below the 5 % minimum
    assert test["verdict"] == "no"


def test_the_family_turns_a_raw_yes_into_no():
    one = [{"group": "g", "label": "x", "test": st.WELCH, "difference": 1.0, "log": False,
            "p": 0.03, "minimum": 0.1}]  # fmt: skip
    assert f.judge(one)[0]["verdict"] == "yes"
    family = [dict(one[0]) for _ in range(3)]
    assert [t["verdict"] for t in f.judge(family)] == ["no"] * 3
    assert family[0]["adjusted"] == pytest.approx(0.09, rel=1e-9)


def test_the_other_side_ahead_is_reported_as_reversed():
    tests = [{"group": "g", "label": "x", "test": st.WELCH, "difference": -2.0, "log": False,
              "p": 0.001, "minimum": 0.5}]  # fmt: skip
    (test,) = f.judge(tests)
    assert (test["passed"], test["reversed"], test["verdict"]) == (False, True, "reversed")


def test_the_geometric_mean_and_its_interval():
    ci = f.mean_ci([1e-4, 1e-2], log=True)
    assert ci.estimate == pytest.approx(1e-3, rel=1e-9)
    assert ci.low <= ci.estimate <= ci.high
    assert f.mean_ci([1.0, 2.0, 3.0]).estimate == pytest.approx(2.0, rel=1e-9)


def test_one_variant_is_no_comparison():
    with pytest.raises(ValueError, match="2 or more variants"):
        f.best_against_others({"a": [1.0, 2.0]}, "return", True, False, FIVE_PERCENT)
