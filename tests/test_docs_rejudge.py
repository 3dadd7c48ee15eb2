"""docs/results/rejudge.py: every committed verdict judged again with the corrected statistics
(Welch's t-test, Holm over the report's family, the minimum effect). The verdict logic is
checked both ways on stored numbers, and docs/results/REJUDGED.md is what the script prints."""

import importlib.util
import json
from pathlib import Path

import pytest

from cpg_actor import statistics as st
from cpg_actor.robustness.summary import retention_scores, verdicts
from cpg_actor.robustness.verdicts import verdict_more_robust
from cpg_actor_studies.hopper_paper.comparisons import judge_comparisons

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "docs" / "results" / "rejudge.py"
PAGE = ROOT / "docs" / "results" / "REJUDGED.md"
# robustness-2M's stored retention per level, cpg-actor and mlp (5 seeds each)
FIXTURE = Path(__file__).parent / "data" / "robustness-2M-retention.json"


@pytest.fixture(scope="module")
def rejudge():
    spec = importlib.util.spec_from_file_location("rejudge", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def suite():
    return json.loads(FIXTURE.read_text(encoding="utf-8"))


def test_holm_turns_the_stored_friction_verdict_into_not_supported(suite):
    """robustness-2M's friction: the bootstrap CI alone is above 0 (the old "supported"), and
    a test of its own passes, but not after Holm over the suite's 7 perturbations; latency
    survives the correction."""
    runs, names = suite["runs"], suite["perturbations"]
    cpg, mlp = (retention_scores(runs, v, "friction") for v in ("cpg-actor", "mlp"))
    assert st.bootstrap_difference(cpg, mlp).low > 0
    ((alone, _),) = st.decide([verdict_more_robust(cpg, mlp)])
    assert alone == st.SUPPORTED
    rows = {row["perturbation"]: row for row in verdicts(runs, names)}
    assert rows["friction"]["family"] == 7
    assert rows["friction"]["p"] < st.ALPHA <= rows["friction"]["p_holm"]
    assert rows["friction"]["verdict"] == st.NOT_SUPPORTED
    assert rows["latency"]["verdict"] == st.SUPPORTED
    assert "family of 7 tests" in rows["latency"]["why"]


def test_a_target_is_met_missed_or_not_resolved_by_its_holm_p_and_minimum(rejudge):
    def verdict(difference, p, minimum=0.0, family=(0.5,)):
        test = st.Test("t", "x", difference, p, minimum)
        test.adjusted = st.holm([p, *family])[0]
        return rejudge.target_verdict(test)

    assert verdict(1.0, 0.001) == rejudge.MET
    assert verdict(-1.0, 0.001) == rejudge.MISSED
    assert verdict(1.0, 0.04) == rejudge.NOT_RESOLVED  # Holm p 0.08: the correction
    assert verdict(1.0, 0.04, family=()) == rejudge.MET  # alone it would pass
    # decisive-2M's hop against cho2019-warm: Holm p 0.023, but 2 cm is under the 5 % minimum
    assert verdict(-0.0202, 0.0057, minimum=0.0291) == rejudge.NOT_RESOLVED


def test_the_old_rule_is_the_whole_ci_on_the_targets_side(rejudge):
    assert rejudge.ci_verdict(st.Interval(1.0, 0.9, 1.1), 0.8) == rejudge.MET
    assert rejudge.ci_verdict(st.Interval(0.7, 0.6, 0.79), 0.8) == rejudge.MISSED
    assert rejudge.ci_verdict(st.Interval(0.8, 0.7, 0.9), 0.8) == rejudge.NOT_RESOLVED
    assert rejudge.ci_verdict(st.Interval(12, 10, 14), 15.0, sign=-1) == rejudge.MET


def test_comparisons_are_judged_on_the_pairs_given():
    """A stored report's own pairs make the family: 2 tests (return, hop) per pair that ran."""
    rng = __import__("numpy").random.default_rng(0)
    seeds = {v: {"final_return": list(rng.normal(mean, 5, 5)),
                 "final_hop_height_logged": list(rng.normal(0.5, 0.01, 5))}
             for v, mean in (("a", 900), ("b", 600), ("c", 600))}  # fmt: skip
    rows = judge_comparisons(seeds, [("a", "b", "a vs b"), ("x", "b", "not run")])
    assert [(r["first"], r["second"]) for r in rows] == [("a", "b")]
    assert rows[0]["family"] == 2 and rows[0]["return_better"] == "a"
    assert rows[0]["hop_better"] == "not resolved"
    assert len(judge_comparisons(seeds, [("a", "b", ""), ("a", "c", "")])) == 2


def test_a_key_a_folder_did_not_store_is_not_tested(rejudge):
    stored = rejudge.Stored({"final_return": [1.0, 2.0, 3.0]})
    rejudge.Stored.missing = set()
    assert stored["hop_height_at_1M"] == [] and stored["final_return"] == [1.0, 2.0, 3.0]
    assert rejudge.Stored.missing == {"hop_height_at_1M"}
    assert st.too_few_seeds({"cpg-actor": stored["velocity_p99"]}).fixed == st.NOT_TESTED


def test_the_committed_page_is_what_the_script_prints(rejudge):
    assert PAGE.read_text(encoding="utf-8") == rejudge.main(), (
        "docs/results/REJUDGED.md is stale: PYTHONPATH=src python docs/results/rejudge.py "
        "> docs/results/REJUDGED.md"
    )


def test_a_damaged_committed_file_is_one_line_naming_it(rejudge, tmp_path, monkeypatch, capsys):
    """The script reads the results folders' committed files: one damaged (an edit gone
    wrong, a merge marker) is one line naming it, not a traceback."""
    from cpg_actor.inputs import run_script

    results = tmp_path / "results"
    for folder in {*rejudge.REPRODUCTIONS, *rejudge.SUITES, rejudge.GO1_SUITE, "decisive-2M"}:
        for path in (ROOT / "docs" / "results" / folder).glob("*.json"):
            (results / folder).mkdir(parents=True, exist_ok=True)
            (results / folder / path.name).write_bytes(path.read_bytes())
    monkeypatch.setattr(rejudge, "RESULTS", results)
    summary = results / "repro-2M" / "summary.json"
    for damage, message in ((b"<<<<<<< HEAD\n", "summary.json is not JSON (line 1"),
                            (b"{}", "summary.json: no 'variants' where it is read")):  # fmt: skip
        summary.write_bytes(damage)
        assert run_script(rejudge.main, "rejudge.py") == 2
        err = capsys.readouterr().err
        assert len(err.splitlines()) == 1 and message in err, err
