"""The analysis scripts that results folders' PROTOCOL.md files fix, run as a reader runs them:
on a committed summary (fresh-2M's, which holds the three agents of fresh-20M) and on
time_to_quality.py's JSON made up here. Their output names the family and the verdicts; bad
input is one line."""

import gzip
import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cpg_actor.robustness.protocol import json_text

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


def test_the_20M_analysis_waits_for_every_run_to_finish(tmp_path):
    summary = json.loads((RESULTS / "fresh-2M" / "summary.json").read_text())
    summary["variants"]["mlp-warm"]["finished"] = 4
    path = tmp_path / "summary.json"
    path.write_text(json.dumps(summary))
    done = run(RESULTS / "fresh-20M" / "analysis.py", str(path))
    assert done.returncode != 0 and "runs not finished yet" in done.stderr
    assert "'mlp-warm': 4" in done.stderr


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
    (tmp_path / "search_budgets.json.gz").write_bytes(gzip.compress(json.dumps(sweep).encode()))
    done = run(RESULTS / "time-to-quality" / "analysis.py", str(tmp_path))  # one as committed
    assert done.returncode == 0, done.stderr
    rows = [line for line in done.stdout.splitlines() if line.startswith("| wall to the target")]
    assert len(rows) == 2
    faster = rows[0].split("|")[-2].strip()
    assert faster == ("yes" if cpg_hit == 0 else "no")
    assert "family of 6 tests" in done.stdout  # the sweep: 2 budgets x 3 tests

    # before the sweep has run, the time to quality (a family of its own) stands alone
    (tmp_path / "search_budgets.json.gz").unlink()
    done = run(RESULTS / "time-to-quality" / "analysis.py", str(tmp_path))
    assert done.returncode == 0, done.stderr
    assert "Not yet run: no `search_budgets.json`" in done.stdout
    assert len([line for line in done.stdout.splitlines() if "to the target |" in line]) == 4

    # a damaged file is one line naming it, not a traceback
    (tmp_path / "search_budgets.json.gz").write_bytes(b"not gzip")
    done = run(RESULTS / "time-to-quality" / "analysis.py", str(tmp_path))
    assert done.returncode != 0 and "Traceback" not in done.stderr
    assert "search_budgets.json.gz is not a whole gzip file" in done.stderr
    assert len(done.stderr.splitlines()) == 1


def fake_grid(error: float, falls: float = 0.0) -> dict:
    """A grid.json as `cpg-actor eval --grid` writes it, with the fields the analysis reads."""
    means = {
        "lin_vel_error": error,
        "lin_vel_offset": error / 2,
        "yaw_rate_error": 2 * error,
        "yaw_rate_offset": error / 4,
        "torque_rate": 80.0,
        "foot_slip": 0.1 + error,
        "planar_cost_of_transport": 2.0,
        "fell": falls,
    }
    checks = [
        {"check": "payload 115%", "fell": falls, "lin_vel_error": 0.4},
        *(
            {
                "check": f"push {side} 1 m/s",
                "fell": 1.0,
                "recovered": 0.0,
                "recovery_seconds": math.nan,
            }
            for side in ("left", "right")
        ),
    ]
    return {
        "rows": [{"check": "", "command": "forward 0.5", **means}, *checks],
        "means": {"flat": means},
    }


def test_the_go1_analysis_reads_its_folder_and_judges_the_targets(tmp_path):
    """The CPG-Actor tracks at 0.05-0.06 m/s, the MLPs at 0.2: it is picked, beats its start
    (0.15) and meets the grid's targets where the MLPs miss the linear one; the other model's
    and the time to walk's numbers come from their own files."""
    out = tmp_path / "go1-omni"
    errors = {"cpg-actor": 0.05, "mlp-field": 0.2, "mlp-warm-field": 0.21, "start": 0.15}
    for variant, error in errors.items():
        for i, seed in enumerate((20, 21, 22)):
            folder = out / "grid" / variant / f"seed{seed}"
            folder.mkdir(parents=True)
            (folder / "grid.json").write_text(json_text(fake_grid(error + 0.005 * i)))
    episodes = {"other": {"0.5": [{"speed_error": 0.1, "forward_speed": 0.5, "fell": False}]}}
    other = out / "other" / "cpg-actor"
    other.mkdir(parents=True)
    (other / "seed20.md").write_text("# report\n\n```json\n" + json.dumps(episodes) + "\n```\n")
    walk = tmp_path / "time_to_walk_grid.json"
    # the CPG-Actor's seed 20 walks before its first update: counted at the next evaluation
    runs = [
        {
            "agent": a,
            "seed": s,
            "start_wall": 0.0,
            "wall": (w + s - 20) * (s > 20),
            "start_steps": 0,
            "steps": 1000 * (s - 20),
            "reached": True,
            "history": [{"steps": 0, "wall": 0.0}, {"steps": 40960, "wall": w}],
        }
        for s in (20, 21, 22, 23)
        for a, w in (("cpg-actor", 10.0), ("mlp-field", 100.0))
    ]
    walk.write_text(json.dumps(runs[:4]))
    more = tmp_path / "time_to_walk_grid-2.json"  # another sitting's part
    more.write_text(json.dumps(runs[4:]))
    done = run(RESULTS / "go1-omni" / "analysis.py", str(out), "--time-to-walk", str(walk),
               str(more))  # fmt: skip
    assert done.returncode == 0, done.stderr
    result = json.loads((out / "analysis.json").read_text())
    assert len(result["tests"]) == 12
    assert result["best"]["linear-velocity error (m/s)"] == "cpg-actor"
    beyond = [t for t in result["tests"] if t["group"] == "cpg-actor beyond its start"]
    assert [t["verdict"] for t in beyond] == ["yes", "yes"]
    goals = result["targets"]["cpg-actor"]
    assert goals["lin_vel_error"]["met"] and goals["yaw_rate_error"]["met"]
    assert not result["targets"]["mlp-field"]["lin_vel_error"]["met"]
    assert goals["other_model"]["met"] and "other_model" not in result["targets"]["mlp-field"]
    walked = result["time_to_walk"]
    assert walked["times"]["cpg-actor"]["wall"] == [10.0, 11.0, 12.0, 13.0]
    assert walked["met"] and walked["ratio"] > 8
    assert walked["test"]["verdict"] == "yes"  # 10x, tested against 5x
    assert "**Pick `cpg-actor`**" in done.stdout and done.stdout.startswith("# go1-omni:")
    assert "| the CPG-Actor's start |" in done.stdout and "recovery (s) nan" in done.stdout
    assert result["offsets"]["cpg-actor"]["lin_vel_offset"] == pytest.approx([0.025, 0.0275, 0.03])
    shutil.rmtree(out / "grid" / "start" / "seed22")  # a start not evaluated: no pairing
    done = run(RESULTS / "go1-omni" / "analysis.py", str(out))
    assert done.returncode != 0 and "every variant and the start need the same seeds" in done.stderr


def test_the_go1_analysis_says_which_evaluation_is_missing(tmp_path):
    done = run(RESULTS / "go1-omni" / "analysis.py", str(tmp_path))
    assert done.returncode != 0
    assert "2 or more seedS/grid.json needed, found 0" in done.stderr


def test_the_rough_ground_analysis_judges_falls_tracking_and_the_level_reached(tmp_path):
    """On level 4 the CPG-Actor falls in 2-4 % of episodes and tracks at 0.12 m/s, the MLP
    falls in 30 % at 0.3 m/s and its curriculum stays lower: the CPG-Actor meets the target
    and is ahead on each; its start falls in 20 %: training adds to it."""
    out = tmp_path / "go1-rough"
    agents = {  # role: (falls at level 4, error there, error on flat ground)
        "cpg-actor": (0.02, 0.12, 0.09),
        "mlp-field": (0.30, 0.30, 0.10),
        "start": (0.20, 0.20, 0.11),
    }
    for role, (falls, rough, flat) in agents.items():
        for i, seed in enumerate((25, 26, 27)):
            grid = fake_grid(flat + 0.002 * i)
            grid["means"]["all level 4"] = {**grid["means"]["flat"], "fell": falls + 0.01 * i,
                                            "lin_vel_error": rough + 0.003 * i}  # fmt: skip
            flat_rows = [{**row, "terrain": "flat"} for row in grid["rows"]]
            rough_rows = [{**row, "terrain": "all level 4"} for row in grid["rows"]]
            rough_rows[-1] |= {"fell": 0.1 * i, "recovered": 1 - 0.1 * i}  # push right
            grid["rows"] = flat_rows + rough_rows
            folder = out / "grid" / role / f"seed{seed}"
            folder.mkdir(parents=True)
            (folder / "grid.json").write_text(json_text(grid))
    for variant, level in (("cpg-actor-omni", 5.0), ("mlp-field", 1.0)):
        for i, seed in enumerate((25, 26, 27)):
            run_dir = out / "runs" / variant / f"seed{seed}"
            run_dir.mkdir(parents=True)
            rows = [{"iteration": k, "global_step": 8192 * k,
                     "charts/terrain_level": level * k / 20 + 0.1 * i}
                    for k in range(1, 21)]  # fmt: skip
            rows.insert(0, {"iteration": 0, "eval/return": 1.0})  # rows without the key
            (run_dir / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    script = RESULTS / "go1-rough" / "analysis.py"
    done = run(script, str(out), "--variants", "cpg-actor-omni,mlp-field")
    assert done.returncode == 0, done.stderr
    result = json.loads((out / "analysis.json").read_text())
    assert len(result["tests"]) == 5
    assert [t["verdict"] for t in result["tests"]] == ["yes", "yes", "no", "yes", "yes"]
    reached = result["data"]["terrain level reached (0-9)"]["cpg-actor"]
    assert reached == pytest.approx([3.875, 3.975, 4.075])  # the mean of the last 10 logged
    goals = result["targets"]
    assert goals["cpg-actor"]["falls"]["met"] and goals["cpg-actor"]["error"]["met"]
    assert not goals["mlp-field"]["falls"]["met"] and not goals["start"]["error"]["met"]
    assert "| the CPG-Actor's start |" in done.stdout
    pushed = result["checks"]["mlp-field"]["all level 4"]["push right"]
    assert pushed["fell"] == pytest.approx([0.0, 0.1, 0.2])
    assert pushed["recovered"] == pytest.approx([1.0, 0.9, 0.8])
    assert result["checks"]["start"]["flat"]["push left"]["fell"] == [1.0, 1.0, 1.0]
    assert "| `mlp-field` | all level 4 | push right | 0.10 (0.00, 0.10, 0.20) | 0.90 " in (
        done.stdout
    )
    assert "| `cpg-actor` | flat | payload | 0.00 (0.00, 0.00, 0.00) | - |" in done.stdout
    kept = json.loads((out / "terrain_levels.json").read_text())
    assert kept["mlp-field"]["27"][-1] == [8192 * 20, pytest.approx(1.2)]

    # a folder without the runs (docs/ keeps no run logs) is read from the levels kept
    docs = tmp_path / "docs-folder"
    shutil.copytree(out / "grid", docs / "grid")
    done = run(script, str(docs), "--variants", "cpg-actor-omni,mlp-field")
    assert "neither runs/VARIANT/seedS/metrics.jsonl nor terrain_levels.json" in done.stderr
    shutil.copy(out / "terrain_levels.json", docs)
    again = run(script, str(docs), "--variants", "cpg-actor-omni,mlp-field")
    assert again.returncode == 0, again.stderr
    assert json.loads((docs / "analysis.json").read_text())["data"] == result["data"]
    done = run(script, str(docs))
    assert done.returncode != 0 and "no variant ['cpg-actor']" in done.stderr
    (docs / "terrain_levels.json").write_text("[1, 2")
    done = run(script, str(docs), "--variants", "cpg-actor-omni,mlp-field")
    assert done.returncode != 0 and "not the terrain levels this analysis keeps" in done.stderr

    # the default names find no cpg-actor runs; a grid without level 4 is named
    done = run(script, str(out))
    assert done.returncode != 0 and "2 or more seedS/metrics.jsonl needed" in done.stderr
    bare = out / "grid" / "start" / "seed25" / "grid.json"
    bare.write_text(json_text(fake_grid(0.1)))
    done = run(script, str(out), "--variants", "cpg-actor-omni,mlp-field")
    assert done.returncode != 0 and "needs the grounds flat and 'all level 4'" in done.stderr
    grid = fake_grid(0.1)
    grid["means"]["all level 4"] = grid["means"]["flat"]
    grid["rows"] = [{**row, "terrain": "flat"} for row in grid["rows"]]
    bare.write_text(json_text(grid))
    done = run(script, str(out), "--variants", "cpg-actor-omni,mlp-field")
    assert done.returncode != 0
    assert "grid/start/seed25/grid.json: no 'payload' row on 'all level 4'" in done.stderr
    done = run(script, str(out), "--variants", "cpg-actor-omni")
    assert done.returncode != 0 and "--variants takes two names" in done.stderr


def test_the_go1_figure_draws_every_variant_it_finds(tmp_path):
    out = tmp_path / "go1-omni"
    for variant in ("cpg-actor", "mlp-field"):
        for seed in (20, 21):
            folder = out / "grid" / variant / f"seed{seed}"
            folder.mkdir(parents=True)
            grid = fake_grid(0.1)
            for row in grid["rows"]:
                row["terrain"] = "flat"
            (folder / "grid.json").write_text(json_text(grid))
    figure = tmp_path / "errors.png"
    done = run(RESULTS / "go1-omni" / "figure.py", str(out), str(figure))
    assert done.returncode == 0, done.stderr
    assert figure.read_bytes().startswith(b"\x89PNG")
    done = run(RESULTS / "go1-omni" / "figure.py", str(out), str(tmp_path / "errors.txt"))
    assert done.returncode != 0 and "one of .png, .svg, .pdf" in done.stderr
    done = run(RESULTS / "go1-omni" / "figure.py", str(tmp_path / "empty"), str(figure))
    assert done.returncode != 0 and "no VARIANT/seedS/grid.json" in done.stderr


def test_the_rough_ground_figure_draws_the_curricula_and_the_level(tmp_path):
    from cpg_actor.robustness.protocol import GRID

    out = tmp_path / "go1-rough"
    for role in ("cpg-actor", "start", "mlp-field"):
        for seed in (25, 26):
            rows = [
                {
                    "terrain": ground,
                    "command": c.name,
                    "check": "",
                    "fell": 0.1,
                    "lin_vel_error": 0.2,
                }
                for c in GRID
                for ground in ("flat", "all level 4")
            ]
            folder = out / "grid" / role / f"seed{seed}"
            folder.mkdir(parents=True)
            (folder / "grid.json").write_text(json_text({"rows": rows, "means": {}}))
    levels = {v: {str(s): [[8192 * k, k / 10] for k in range(20)] for s in (25, 26)}
              for v in ("cpg-actor", "mlp-field")}  # fmt: skip
    (out / "terrain_levels.json").write_text(json.dumps(levels))
    script = RESULTS / "go1-rough" / "figure.py"
    figure = tmp_path / "rough.png"
    done = run(script, str(out), str(figure))
    assert done.returncode == 0, done.stderr
    assert figure.read_bytes().startswith(b"\x89PNG")
    done = run(script, str(out), str(tmp_path / "rough.txt"))
    assert done.returncode != 0 and "one of .png, .svg, .pdf" in done.stderr
    shutil.rmtree(out / "grid")
    done = run(script, str(out), str(figure))
    assert done.returncode != 0 and "no ROLE/seedS/grid.json with 'all level 4' rows" in done.stderr


def go1_folder(out: Path) -> Path:
    """A go1-omni folder the analysis reads (3 seeds per variant and the start)."""
    for variant, error in {"cpg-actor": 0.05, "mlp-field": 0.2, "mlp-warm-field": 0.21,
                           "start": 0.15}.items():  # fmt: skip
        for i, seed in enumerate((20, 21, 22)):
            folder = out / "grid" / variant / f"seed{seed}"
            folder.mkdir(parents=True)
            (folder / "grid.json").write_text(json_text(fake_grid(error + 0.005 * i)))
    return out


def test_each_analysis_refuses_a_missing_or_damaged_input_in_one_line(tmp_path):
    """A file missing, not text, not JSON, of another shape or lacking a key, a corrupt
    archive, a damaged line of a run's metrics: one line naming it, exit status 2, never a
    traceback (`cpg_actor.inputs`, shared by the analyses)."""
    out = go1_folder(tmp_path / "go1-omni")
    grid = out / "grid" / "cpg-actor" / "seed20" / "grid.json"
    walk = tmp_path / "time_to_walk_grid.json"
    good = json.loads(grid.read_text())
    summary = tmp_path / "summary.json"
    levels = tmp_path / "trio" / "runs" / "mlp" / "seed0" / "metrics.jsonl"
    levels.parent.mkdir(parents=True)
    quality = tmp_path / "quality"
    quality.mkdir()
    omni, rough = RESULTS / "go1-omni" / "analysis.py", RESULTS / "go1-rough" / "analysis.py"
    cases = [  # (script, arguments, the file damaged, its bytes, what the line says)
        (omni, [out], grid, b"{oops", "grid.json is not JSON (line 1, column 2"),
        (omni, [out], grid, b"\xff\xfe", "grid.json is not text (byte 0 is not UTF-8)"),
        (omni, [out], grid, b"[]", "grid.json holds a list, not the JSON an object expected"),
        (omni, [out], grid, json.dumps({"rows": good["rows"]}).encode(),
         "grid.json: no 'means' where it is read"),
        (omni, [out], grid, json.dumps({**good, "means": {"flat": [1]}}).encode(),
         "its inputs are not the files it reads, or are damaged (TypeError"),
        (omni, [out, "--time-to-walk", walk], None, None,
         "time_to_walk_grid.json does not exist"),
        (omni, [out, "--time-to-walk", walk], walk, b"[{", "time_to_walk_grid.json is not JSON"),
        (omni, [out, "--time-to-walk", walk], walk, json.dumps([{"seed": 1}]).encode(),
         "time_to_walk_grid.json: no 'agent' where it is read"),
        (RESULTS / "go1-omni" / "figure.py", [out, tmp_path / "f.png"], grid, b"{}",
         "grid.json: no 'rows' where it is read"),
        (RESULTS / "go1-rough" / "figure.py", [out, tmp_path / "f.png"], grid, b"{oops",
         "grid.json is not JSON"),
        (rough, [out, "--variants", "cpg-actor-omni,mlp-field"], grid, b"{oops",
         "grid.json is not JSON"),
        (RESULTS / "fresh-20M" / "analysis.py", [summary], summary, b"{oops",
         "summary.json is not JSON"),
        (RESULTS / "fresh-20M" / "analysis.py", [summary], summary, b"{}",
         "summary.json: no 'variants' where it is read"),
        (RESULTS / "fresh-2M" / "analysis.py", [tmp_path], summary, b"\x89PNG",
         "summary.json is not text"),
        (RESULTS / "time-to-quality" / "analysis.py", [quality],
         quality / "time_to_quality.json", json.dumps({"`cpg-actor`": [{"seed": 1}]}).encode(),
         "time_to_quality.json: no 'hit' where it is read"),
        (RESULTS / "time-to-quality" / "analysis.py", [quality],
         quality / "time_to_quality.json.gz", gzip.compress(b"{}" * 100)[:20],
         "time_to_quality.json.gz is not a whole gzip file"),
        (RESULTS / "decisive-2M" / "targets.py", [summary], summary, b"[1",
         "summary.json is not JSON"),
        (RESULTS / "randomized-2M" / "targets.py", [summary], summary, b"{}",
         "summary.json: no 'runs' where it is read"),
        (RESULTS / "robustness-go1-2M" / "compare.py", [tmp_path / "none.json"], None, None,
         "none.json does not exist"),
        (RESULTS / "trio-20M" / "progress.py", [tmp_path / "trio"], levels,
         b'{"global_step": 1, "eval/return": 2}\ngarbage\n{"global_step": 2}\n',
         "metrics.jsonl, line 2: not JSON"),
    ]  # fmt: skip
    for script, args, path, data, message in cases:
        kept = path.read_bytes() if path is not None and path.exists() else None
        if path is not None:
            path.write_bytes(data)
        try:
            done = run(script, *map(str, args))
        finally:
            if path is not None and kept is not None:
                path.write_bytes(kept)
            elif path is not None:
                path.unlink()
        assert done.returncode == 2, (script, message, done.stderr)
        assert len(done.stderr.splitlines()) == 1, (script, message, done.stderr)
        assert message in done.stderr, (script, message, done.stderr)
        assert not (out / "analysis.json").exists()
