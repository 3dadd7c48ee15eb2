"""The claims judged on the suite's results: the CPG-Actor more robust than the MLP, and
randomised training more robust than nominal training, per perturbation; tested both ways on
synthetic results, "not tested" below 3 seeds a side."""

import json

import pytest

from cpg_actor import statistics as st
from cpg_actor.robustness.summary import retention_scores, verdicts
from cpg_actor_studies.hopper_paper.report import robustness_lines


def run(variant, seed, retentions):
    levels = [{"level": float(i + 1), "retention": r} for i, r in enumerate(retentions)]
    return {"variant": variant, "seed": seed,
            "perturbations": {"payload": {"levels": levels}}}  # fmt: skip


def runs(variant, retentions, seeds=5, spread=0.01):
    return [run(variant, s, [r + spread * (s - seeds // 2) for r in retentions])
            for s in range(seeds)]  # fmt: skip


def test_a_variant_that_keeps_more_of_its_return_is_more_robust():
    data = runs("cpg-actor", [0.9, 0.8, 0.7]) + runs("mlp", [0.7, 0.5, 0.3])
    assert retention_scores(data, "cpg-actor", "payload")[2] == pytest.approx(0.8)
    (row,) = verdicts(data, ["payload"])
    assert row["claim"] == "cpg-actor more robust than mlp"
    assert row["verdict"] == st.SUPPORTED
    # the other way round, and equal retention: not supported
    (row,) = verdicts(runs("cpg-actor", [0.7, 0.5, 0.3]) + runs("mlp", [0.9, 0.8, 0.7]),
                      ["payload"])  # fmt: skip
    assert row["verdict"] == st.NOT_SUPPORTED
    (row,) = verdicts(runs("cpg-actor", [0.8] * 3) + runs("mlp", [0.8] * 3), ["payload"])
    assert row["verdict"] == st.NOT_SUPPORTED


def test_fewer_than_three_seeds_a_side_is_not_tested():
    data = runs("cpg-actor", [0.9, 0.8], seeds=2) + runs("mlp", [0.5, 0.3])
    (row,) = verdicts(data, ["payload"])
    assert row["verdict"] == st.NOT_TESTED and "cpg-actor 2" in row["why"]


def test_randomised_training_is_judged_against_nominal_training(tmp_path):
    data = runs("mlp-randomized", [0.95, 0.9]) + runs("mlp", [0.6, 0.4])
    (row,) = verdicts(data, ["payload"])
    assert row["claim"] == "mlp-randomized more robust than mlp" and row["verdict"] == st.SUPPORTED
    (row,) = verdicts(runs("mlp-randomized", [0.5, 0.4]) + runs("mlp", [0.6, 0.5]), ["payload"])
    assert row["verdict"] == st.NOT_SUPPORTED
    # in the reproduction report when the suite ran into OUT/robustness
    assert robustness_lines(tmp_path) == []
    (tmp_path / "robustness").mkdir()
    (tmp_path / "robustness" / "robustness.json").write_text(
        json.dumps({"episodes": 4, "verdicts": verdicts(data, ["payload"])}))  # fmt: skip
    text = "\n".join(robustness_lines(tmp_path))
    assert "## Robustness" in text and "| mlp-randomized more robust than mlp | payload |" in text
