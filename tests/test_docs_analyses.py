"""The analysis scripts that results folders' PROTOCOL.md files fix, run as a reader runs them:
on a committed summary (fresh-2M's, which holds the three agents of fresh-20M) and on
time_to_quality.py's JSON made up here. Their output names the family and the verdicts; bad
input is one line."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results"


def run(script: Path, *args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "MPLBACKEND": "Agg"}
    return subprocess.run([sys.executable, str(script), *args], capture_output=True, text=True,
                          env=env, timeout=300)  # fmt: skip


def test_the_20M_analysis_judges_the_family_of_its_protocol(tmp_path):
    summary = tmp_path / "summary.json"
    summary.write_bytes((RESULTS / "fresh-2M" / "summary.json").read_bytes())
    done = run(RESULTS / "fresh-20M" / "analysis.py", str(summary), "--figure",
               str(tmp_path / "c.png"))  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "family of 11 tests" in done.stdout
    result = json.loads((tmp_path / "analysis.json").read_text())
    assert len(result["tests"]) == 11
    tests = {(t["group"], t["label"]): t for t in result["tests"]}
    # fresh-2M's stored numbers: mlp-warm's return 1080 beats cho2019-warm's 963 past Holm
    assert tests["return", "mlp-warm vs cho2019-warm"]["verdict"] == "yes"
    assert result["best"]["command smoothness (rad^2)"] == "cpg-actor"
    assert result["claim"]["supported"] is False  # at 2M the ratio is about 1, not 6
    assert (tmp_path / "c.png").stat().st_size > 0


def test_the_20M_analysis_refuses_a_summary_without_its_agents(tmp_path):
    summary = tmp_path / "summary.json"
    summary.write_text(json.dumps({"variants": {"mlp": {"per_seed": {"final_return": [1, 2]}}}}))
    done = run(RESULTS / "fresh-20M" / "analysis.py", str(summary))
    assert done.returncode != 0
    assert "lacks 2 or more seeds of ['cpg-actor', 'mlp-warm', 'cho2019-warm']" in done.stderr
    assert not (tmp_path / "analysis.json").exists()


def curve(start: float, slope: float, hit_at: int | None) -> dict:
    points = [{"wall": 10.0 * (i + 1), "steps": 1000 * (i + 1), "return": start + slope * i,
               "apex": 0.4 + 0.01 * i} for i in range(8)]  # fmt: skip
    return {"curve": points, "hit": points[hit_at] if hit_at is not None else None}


@pytest.mark.parametrize("cpg_hit", [0, 6])
def test_the_time_to_quality_analysis_orders_the_methods(tmp_path, cpg_hit):
    """The CPG-Actor at the target at once (every seed) is faster than a method that gets
    there at the 7th evaluation; getting there at the same time, it is not."""
    methods = {"`cpg-actor`": cpg_hit, "`mlp-warm`": 6, "`mlp`": None}
    quality = {label: [dict(curve(500 + s, 20, hit), seed=15 + s) for s in range(5)]
               for label, hit in methods.items()}  # fmt: skip
    sweep = {f"{label} (search {budget})": [dict(curve(500 + s, 20 + s, 3), seed=15 + s)
                                            for s in range(5)]
             for budget in ("50k", "150k") for label in ("`cpg-actor`", "`mlp-warm`",
                                                          "`cho2019-warm`")}  # fmt: skip
    (tmp_path / "time_to_quality.json").write_text(json.dumps(quality))
    (tmp_path / "search_budgets.json").write_text(json.dumps(sweep))
    done = run(RESULTS / "time-to-quality" / "analysis.py", str(tmp_path))
    assert done.returncode == 0, done.stderr
    rows = [line for line in done.stdout.splitlines() if line.startswith("| wall to the target")]
    assert len(rows) == 2
    faster = rows[0].split("|")[-2].strip()
    assert faster == ("yes" if cpg_hit == 0 else "no")
    assert "family of 6 tests" in done.stdout  # the sweep: 2 budgets x 3 tests
