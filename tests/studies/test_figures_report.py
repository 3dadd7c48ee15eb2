"""Figures and report from a constructed results directory (no training): variants that were
not run are skipped with a note; progress lines read metrics.jsonl."""

import json
import re

import numpy as np
import pytest

from cpg_actor.metrics import signals
from cpg_actor_studies.hopper_paper.figures import make_figures
from cpg_actor_studies.hopper_paper.report import write_report
from cpg_actor_studies.reproduction.execute import Progress, read_progress
from cpg_actor_studies.reproduction.plan import RunTask
from cpg_actor_studies.reproduction.results import Results


def _fake_run(out, variant, seed, bang_bang=False, steps=500, responsive=False, stop_steps=0):
    run = out / "runs" / variant / f"seed{seed}"
    (run / "eval" / "stage0").mkdir(parents=True)
    rows = [
        {"iteration": i, "global_step": 100 * i, "charts/episode_return": float(i + seed),
         "charts/SPS": 1000.0}
        for i in range(1, steps // 100 + 1)
    ]  # fmt: skip
    (run / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    t = 0.01 * np.arange(1, 201)
    wave = np.sign(np.sin(4 * np.pi * t)) if bang_bang else np.sin(4 * np.pi * t)
    position = np.stack([0.4 + 0.2 * wave, -0.8 + 0.3 * wave], axis=-1)[:, None, :]
    position[:stop_steps, :, 0] = 1.3  # the HFE at its upper stop (the hopper's limit)
    traces = {
        "time": t,
        "desired_position": position,
        "desired_velocity": np.gradient(position, 0.01, axis=0),
        "hip_height": 0.5 + 0.05 * np.abs(np.sin(4 * np.pi * t))[:, None],
        "foot_height": 0.02 * np.abs(np.sin(4 * np.pi * t))[:, None],
        "standing_hip_height": np.array(0.5),
        "episode_return": np.array([10.0]),
        "hop_height": np.array([0.05]),
        # CPG signals (T, E, N): flat, or moving with the environment (feedback)
        "theta_dot": np.full((200, 1, 2), 4 * np.pi)
        + (3.0 * np.sin(2 * np.pi * 1.3 * t)[:, None, None] if responsive else 0.0),
        "r_ddot": (20.0 * np.sin(2 * np.pi * 2.1 * t)[:, None, None] if responsive else 0.0)
        + np.zeros((200, 1, 2)),
    }
    np.savez(run / "eval" / "stage0" / "traces.npz", **traces)
    stages = [{"stage": 0, "fraction": 1.0, "iteration": 5, "checkpoint": "x",
               "traces": "eval/stage0/traces.npz"}]  # fmt: skip
    (run / "eval" / "stages.json").write_text(json.dumps(stages))
    (run / "reproduce_run.json").write_text(json.dumps({"status": "done"}))
    return run


def test_missing_variants_are_skipped_with_notes(tmp_path):
    out = tmp_path / "out"
    for seed in (0, 1):
        _fake_run(out, "mlp", seed, bang_bang=True)
    results = Results.load(out, ["cpg-actor", "mlp"])
    assert list(results.runs) == ["mlp"] and results.first("mlp").seed == 0
    paths, notes = make_figures(results)
    names = {p.name for p in paths}
    assert {"ep_reward.png", "ep_reward.pdf", "des_pos.png", "des_vel.png"} <= names
    assert "cpg_output.png" not in names
    assert "ep_reward: cpg-actor was not run" in notes
    assert any("cpg_actor_training_over_time: cpg-actor was not run" in n for n in notes)
    assert any("parameters_under_training" in n for n in notes)

    report = write_report(out).read_text()
    assert "| MLP actor (`mlp`) | 2 (2) |" in report
    assert report.count("**not tested in this run**") == 7
    assert "cpg_actor_training_over_time: cpg-actor was not run" in report


def test_report_verdicts_from_constructed_traces(tmp_path):
    out = tmp_path / "out"
    for seed in range(3):
        _fake_run(out, "mlp", seed, bang_bang=True)
        _fake_run(out, "cpg-actor", seed)
    write_report(out)
    summary = json.loads((out / "summary.json").read_text())
    verdicts = {c["claim"]: c["verdict"] for c in summary["claims"]}
    assert len(verdicts) == 7
    smooth = [v for claim, v in verdicts.items() if "bang-bang" in claim]
    assert smooth == ["supported"]  # a sine vs a square wave
    cho = [v for claim, v in verdicts.items() if "Cho" in claim]
    assert cho == ["not tested in this run"] * 3
    cpg, mlp = summary["variants"]["cpg-actor"], summary["variants"]["mlp"]
    assert cpg["seeds"] == 3 and cpg["kind"] == "cpg" and mlp["kind"] == "mlp"
    # per seed, then the median over seeds with its CI (here the seeds are equal)
    smoothness = mlp["per_seed"]["smoothness"][0]
    assert smoothness > 0 and mlp["median"]["smoothness"] == pytest.approx([smoothness] * 3)
    # the velocity is the finite difference of the positions over the period (the traces'
    # `time`: they have no control_dt), not their stored desired_velocity
    traces = np.load(out / "runs" / "cpg-actor" / "seed0" / "eval" / "stage0" / "traces.npz")
    by_hand = np.percentile(np.abs(np.diff(traces["desired_position"], axis=0) / 0.01), 99)
    assert cpg["per_seed"]["velocity_p99"][0] == pytest.approx(by_hand)
    assert cpg["per_seed"]["time_at_stop"] == [0.0] * 3
    # the physical metrics these traces have data for; the torques' absent, not 0
    assert cpg["per_seed"]["hop_apex"] == pytest.approx([0.05] * 3, rel=0.01)  # sampled peaks
    assert all(np.isnan(cpg["per_seed"]["torque_rate"]))
    report = (out / "report.md").read_text()
    assert "## Physical metrics" in report and "| hop apex (m) | highest hip (m) |" in report


def _interval_free(text):
    """The lines of a report section that would show an empty interval: a value +- 0, or a CI
    whose ends are equal."""
    return [
        line
        for line in text.splitlines()
        if "+- 0 " in line or "+- 0 |" in line or re.search(r"\[(\S+), \1\]", line)
    ]


def test_a_report_of_one_seed_has_no_verdicts_and_no_intervals(tmp_path):
    """1 seed per variant (and 2 for one of them): every claim "not tested", no interval, no
    "+- 0", the per-seed values in the tables."""
    from cpg_actor_studies.hopper_paper.floor import FLOOR_FILE

    out = tmp_path / "out"
    n = 20
    rising = np.linspace(0.2, 1.0, n)
    _curve_run(out, "cpg-actor", 0, 3000.0 * rising, 0.15 + 0.25 * rising**2, responsive=True)
    _curve_run(out, "cpg-actor-open-loop", 0, 800.0 * rising, np.full(n, 0.1))
    _curve_run(out, "cho2019-warm", 0, 500.0 * rising, np.full(n, 0.1))
    for seed in (0, 1):
        _curve_run(out, "mlp", seed, 600.0 * rising + seed, np.full(n, 0.2), square=True)
    floor = {"candidates": 4, "env": {}, "best_return": {"episode_return": 400.0,
             "parameters": {"frequency": 2.0}, "hop_height_p90": 0.2},
             "best_hop": {"hop_height_p90": 0.3, "episode_return": 300.0}}  # fmt: skip
    (out / FLOOR_FILE).write_text(json.dumps(floor))
    transfer = {"episodes": 2, "seed": 1000, "runs": {"cpg-actor": {"0": {
        "trained_in": "mujoco", "mujoco": {"return": 100.0, "hop_height": 0.3},
        "pybullet": {"return": 90.0, "hop_height": 0.3}}}}}  # fmt: skip
    (out / "transfer.json").write_text(json.dumps(transfer))
    verdicts = _claims(out)
    assert set(verdicts.values()) == {"not tested in this run"}, verdicts
    summary = json.loads((out / "summary.json").read_text())
    for claim in summary["claims"]:
        assert "[" not in claim["detail"], claim  # no interval in the evidence
    assert summary["variants"]["mlp"]["median"]["final_return"] is None
    report = (out / "report.md").read_text()
    assert _interval_free(report) == []
    assert "| MLP actor (`mlp`) | 2 (2) | 486, 487 | 10, 10 |" in report  # the seeds' values
    assert "fewer than 3 seeds, not tested: `cpg-actor`" in report  # the floor
    assert "not tested (< 3 seeds)" in report  # MLP vs CPG-Actor beyond the paper
    assert "| 90% |" in report  # transfer: the share kept, without an interval
    assert "not tested (fewer than 3 seeds" in report  # the ratio to Cho et al. (warm)


def test_new_and_unknown_variants_are_reported_by_kind(tmp_path):
    """Variants the report has no special case for (agents added later, a name of no known
    kind) are reported without error; CPG kinds appear in the CPG figures; the time at a
    joint stop is the share of steps a desired position sits at its limit."""
    out = tmp_path / "out"
    for seed in range(3):
        _fake_run(out, "cpg-actor-paper", seed, responsive=True)
        _fake_run(out, "open-loop-es", seed)
        _fake_run(out, "mlp-warm", seed, bang_bang=True, stop_steps=50 + seed)
        _fake_run(out, "someone-elses-agent", seed)
    (out / "reproduce.yaml").write_text(
        "settings:\n  total_steps: 500\n  variants: [cpg-actor-paper, open-loop-es, mlp-warm, "
        "someone-elses-agent, cho2019-paper, cpg-actor]\n"
    )
    write_report(out)
    summary = json.loads((out / "summary.json").read_text())
    kinds = {variant: row["kind"] for variant, row in summary["variants"].items()}
    assert kinds == {"cpg-actor-paper": "cpg", "open-loop-es": "cpg", "mlp-warm": "mlp",
                     "someone-elses-agent": None}  # fmt: skip
    # 50, 51, 52 of 200 steps at the HFE stop: the median 51 / 200
    stop = summary["variants"]["mlp-warm"]["median"]["time_at_stop"]
    assert stop[0] == pytest.approx(51 / 200) and stop[1:] == pytest.approx([50 / 200, 52 / 200])
    assert summary["variants"]["open-loop-es"]["per_seed"]["time_at_stop"] == [0.0] * 3
    report = (out / "report.md").read_text()
    assert "| MLP actor (warm) (`mlp-warm`) | 3 (3) |" in report
    assert "25.5% [25.0%, 26.0%] |" in report
    assert set(c["verdict"] for c in summary["claims"]) == {"not tested in this run"}
    assert "cpg_output: cpg-actor-paper was not run" not in report
    assert "cpg_output: open-loop-es was not run" not in report
    assert "cpg_output: cho2019-paper was not run" in report


def test_progress_lines_read_metrics(tmp_path):
    run = _fake_run(tmp_path, "mlp", 0, steps=300)
    assert read_progress(run) == (300, 1000.0)
    assert read_progress(tmp_path / "nothing") == (0, None)
    task = RunTask("mlp", 0, str(run), str(tmp_path / "log"), 600, 6, 600, (), (1.0,), 1)
    progress = Progress([task], interval=1.0, live=False)
    progress.set("mlp/seed0", "training")
    lines = progress.lines()
    assert "mlp/seed0" in lines[0] and "300/600 steps" in lines[0] and "1,000 SPS" in lines[0]
    assert lines[-1].strip().startswith("overall 300/600 steps (50.0%)")
    from rich.console import Console

    console = Console(record=True, width=120)
    console.print(progress.table())
    assert "mlp/seed0" in console.export_text()


def _curve_run(
    out, variant, seed, returns, hops, total=2_000_000, p99=14.0, square=False, responsive=False
):
    """A run whose logged evaluations follow ``returns`` and ``hops`` (evenly spaced to
    ``total`` steps) and whose final traces have desired velocities of p99 about ``p99``."""
    run = _fake_run(out, variant, seed, bang_bang=square, responsive=responsive)
    steps = np.linspace(total / len(returns), total, len(returns))
    rows = [
        {"iteration": i + 1, "global_step": float(step), "eval/return": float(r),
         "eval/hop_height": float(h), "charts/episode_return": float(r),
         "reward_terms/r1": 1.25 * float(r), "reward_terms/r2": -0.25 * float(r),
         "reward_terms/r3": 0.0, "reward_terms/r4": 0.0, "reward_terms/r5": 0.0}
        for i, (step, r, h) in enumerate(zip(steps, returns, hops, strict=True))
    ]  # fmt: skip
    (run / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    traces = dict(np.load(run / "eval" / "stage0" / "traces.npz"))
    # the desired velocity is the positions' finite difference over the control period: a
    # shorter period scales it to p99 about ``p99`` (the smoothness, per step, stays)
    natural = signals.velocity_p99(signals.desired_velocity(traces["desired_position"], 0.01))
    traces["control_dt"] = np.array(0.01 * natural / p99)
    # a stored desired_velocity (older traces: a CPG's analytic x_dot) is not read
    traces["desired_velocity"] = np.full_like(traces["desired_velocity"], 1e3)
    np.savez(run / "eval" / "stage0" / "traces.npz", **traces)


def _claims(out):
    (out / "reproduce.yaml").write_text(
        "settings:\n  total_steps: 2000000\n  variants: [cpg-actor, cpg-actor-open-loop, "
        "cho2019-warm, mlp]\n"
    )
    write_report(out)
    summary = json.loads((out / "summary.json").read_text())
    return {c["claim"]: c["verdict"] for c in summary["claims"]}


def test_every_verdict_can_come_out_negative(tmp_path):
    """Synthetic results that contradict each claim of the paper: every verdict must say
    "not supported" (a verdict that cannot fail would say "supported" here)."""
    out = tmp_path / "out"
    n = 20
    for seed in range(3):
        jitter = 5.0 * seed
        # the CPG-Actor: no better than Cho et al., worst during training, flat hop height,
        # bang-bang desired positions, desired velocities far beyond the motor limit
        flat = np.full(n, 0.2 + 0.01 * seed)
        _curve_run(out, "cpg-actor", seed, np.full(n, 300.0 + jitter), flat, p99=45, square=True)
        _curve_run(out, "cpg-actor-open-loop", seed, np.full(n, 100.0 + jitter), np.full(n, 0.1))
        _curve_run(
            out, "cho2019-warm", seed, np.full(n, 400.0 + jitter), np.full(n, 0.3),
            responsive=True,
        )  # fmt: skip
        _curve_run(out, "mlp", seed, np.full(n, 500.0 + jitter), np.full(n, 0.3), square=True)
    verdicts = _claims(out)
    assert len(verdicts) == 7
    assert set(verdicts.values()) == {"not supported"}, verdicts


def test_results_that_agree_with_the_paper_are_supported(tmp_path):
    """The same report on results shaped like the paper's: every claim that this set of variants
    can test is supported."""
    out = tmp_path / "out"
    n = 20
    rising = np.linspace(0.2, 1.0, n)
    for seed in range(3):
        jitter = 5.0 * seed
        _curve_run(
            out, "cpg-actor", seed, 3000.0 * rising + jitter, 0.15 + 0.25 * rising**2,
            responsive=True,
        )  # fmt: skip
        _curve_run(out, "cpg-actor-open-loop", seed, 800.0 * rising + jitter, np.full(n, 0.1))
        _curve_run(out, "cho2019-warm", seed, 500.0 * rising + jitter, np.full(n, 0.1))
        _curve_run(out, "mlp", seed, 600.0 * rising + jitter, np.full(n, 0.2), square=True)
    verdicts = _claims(out)
    assert set(verdicts.values()) == {"supported"}, verdicts
    # every verdict names its test and the family the claims' tests make together
    summary = json.loads((out / "summary.json").read_text())
    families = {c["detail"].split("Holm correction over a family of ")[1].split(" ")[0]
                for c in summary["claims"]}  # fmt: skip
    assert len(families) == 1 and int(families.pop()) >= 7
    assert all("t-test" in c["detail"] for c in summary["claims"])
    # the return split into its terms: the means of the last 10 logged values, over seeds
    summary = json.loads((out / "summary.json").read_text())
    mlp_final = np.mean([np.mean(600.0 * rising[-10:] + 5.0 * seed) for seed in range(3)])
    assert summary["variants"]["mlp"]["term_r1"][0] == pytest.approx(1.25 * mlp_final)
    assert summary["variants"]["mlp"]["training_return"][0] == pytest.approx(mlp_final)
    assert "| MLP actor | " in (out / "report.md").read_text().split("reward terms")[1]


def test_comparisons_beyond_the_paper_name_the_better_variant_only_when_resolved(tmp_path):
    """bptt32 clearly above cpg-actor-paper in return (hop heights equal: not resolved); mlp-apex
    below cpg-actor-apex in hop height; pairs that did not run are left out."""
    out = tmp_path / "out"
    n = 12
    for seed in range(4):
        jitter = 3.0 * seed
        same_hop = np.full(n, 0.25 + 0.01 * (seed % 2))
        _curve_run(out, "cpg-actor", seed, np.full(n, 400.0 + jitter), same_hop)
        _curve_run(out, "cpg-actor-paper", seed, np.full(n, 400.0 + jitter), same_hop)
        _curve_run(out, "cpg-actor-bptt32", seed, np.full(n, 600.0 + jitter), same_hop[::-1])
        _curve_run(out, "mlp-apex", seed, np.full(n, 500.0 + jitter), np.full(n, 0.2))
        shuffled = 3.0 * ((seed + 2) % 4)  # the same returns as mlp-apex, other seeds
        _curve_run(out, "cpg-actor-apex", seed, np.full(n, 500.0 + shuffled), np.full(n, 0.3))
        for variant in ("mlp-apex", "cpg-actor-apex"):
            run = out / "runs" / variant / f"seed{seed}"
            (run / "config.yaml").write_text("env:\n  hop_reward: apex\n")
    write_report(out)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["variants"]["mlp-apex"]["reward"].endswith("hop_reward=apex, apex_weight=200.0")
    # "best during training" compares the CPG-Actor with variants of its own reward only
    best = next(c for c in summary["claims"] if "best during training" in c["claim"])
    assert "cpg-actor-bptt32" in best["detail"] and "apex" not in best["detail"]
    rows = {
        (r["first"], r["second"]): r
        for r in json.loads((out / "summary.json").read_text())["comparisons"]
    }
    assert set(rows) == {
        ("cpg-actor-bptt32", "cpg-actor-paper"),
        ("mlp-apex", "cpg-actor-apex"),
        ("cpg-actor", "cpg-actor-paper"),
    }
    bptt = rows[("cpg-actor-bptt32", "cpg-actor-paper")]
    assert bptt["return_better"] == "cpg-actor-bptt32" and bptt["return"][0] == pytest.approx(200)
    assert bptt["hop_better"] == "not resolved"
    apex = rows[("mlp-apex", "cpg-actor-apex")]
    assert apex["hop_better"] == "cpg-actor-apex" and apex["return_better"] == "not resolved"
    # Welch's p and its Holm p over the table's 6 tests (3 pairs x return, hop height)
    assert all(r["family"] == 6 and r["return_p"][1] >= r["return_p"][0] for r in rows.values())
    text = (out / "report.md").read_text()
    assert "## Comparisons beyond the paper" in text
    assert "Holm correction over a family of 6 tests" in text


def test_open_loop_floor_is_the_best_grid_return_and_the_report_places_variants_against_it(
    tmp_path,
):
    from cpg_actor.robots.hopper.cho2019_reference import evaluate_parameters, grid_candidates
    from cpg_actor.robots.hopper.config import HopperConfig
    from cpg_actor_studies.hopper_paper.floor import FLOOR_FILE, open_loop_floor

    grid = {"frequency": (1.5, 3.0), "amplitude_hip": (0.3,), "amplitude_knee": (0.6,),
            "phase_bias": (0.0, np.pi)}  # fmt: skip
    config = HopperConfig(episode_steps=60)
    floor = open_loop_floor(config, grid)
    returns = [c.episode_return for c in evaluate_parameters(grid_candidates(grid), config)]
    assert floor["candidates"] == 4
    assert floor["best_return"]["episode_return"] == pytest.approx(max(returns))

    out = tmp_path / "out"
    for seed in range(3):
        _curve_run(out, "cpg-actor", seed, np.full(10, 600.0 + seed), np.full(10, 0.3))
        _curve_run(out, "mlp", seed, np.full(10, 100.0 + seed), np.full(10, 0.3))
    floor["best_return"]["episode_return"] = 400.0
    (out / FLOOR_FILE).write_text(json.dumps(floor))
    write_report(out)
    text = (out / "report.md").read_text()
    assert "returns **400**" in text
    assert "above it `cpg-actor` (+201); below it `mlp` (-299)" in text


def test_the_report_shows_a_run_that_stopped_learning(tmp_path):
    """A run that peaks mid-way and falls back, its std collapsed, against one still improving:
    the report's "Learning over the run" gives each its peak, where, the drop and the std."""
    out = tmp_path / "results"
    falling = [100.0] * 5 + [500.0] * 10 + [300.0] * 10
    _curve_run(out, "cpg-actor", 0, falling, [0.3] * 25)
    _curve_run(out, "mlp", 0, list(np.linspace(100.0, 800.0, 25)), [0.3] * 25)
    for variant, log_std in (("cpg-actor", -9.0), ("mlp", np.log(0.5))):
        path = out / "runs" / variant / "seed0" / "metrics.jsonl"
        rows = [json.loads(line) for line in path.read_text().splitlines()]
        rows[-1]["policy/log_std_0"] = rows[-1]["policy/log_std_1"] = float(log_std)
        path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    _claims(out)
    variants = json.loads((out / "summary.json").read_text())["variants"]
    cpg, mlp = variants["cpg-actor"], variants["mlp"]
    assert cpg["peak_return"][0] == pytest.approx(500.0)
    assert cpg["peak_step"][0] == pytest.approx(2_000_000 * 15 / 25)  # the 15th evaluation
    assert cpg["final_return"][0] == pytest.approx(300.0)
    assert cpg["final_std"][0] == pytest.approx(np.exp(-9.0))
    assert mlp["peak_return"][0] == pytest.approx(mlp["final_return"][0])
    assert mlp["peak_step"][0] == pytest.approx(2_000_000)
    assert mlp["final_std"][0] == pytest.approx(0.5)
    report = (out / "report.md").read_text()
    section = report.split("## Learning over the run")[1].split("## ")[0]
    assert "| CPG-Actor | 500 | 1,200,000 | 300 | -200 | 0.000123 |" in section  # one seed


def test_the_episode_reward_figure_counts_steps_in_units_its_runs_read_in(tmp_path, monkeypatch):
    """5,000-step runs: thousands (0-5), not millions (0.000-0.005)."""
    from cpg_actor_studies.hopper_paper import figures

    out = tmp_path / "out"
    for seed in (0, 1):
        _fake_run(out, "mlp", seed, steps=5000)
    drawn = []
    monkeypatch.setattr(figures, "_save", lambda fig, directory, name: drawn.append(fig) or [])
    figures.ep_reward(Results.load(out, ["mlp"]), tmp_path / "figures")
    (axis,) = drawn[0].axes
    assert axis.get_xlabel() == "time steps (thousands)"
    assert axis.get_lines()[0].get_xdata().max() == pytest.approx(5.0)


def test_training_over_time_labels_each_snapshot_once_and_titles_it(tmp_path, monkeypatch):
    """A budget too short for the stages: two of them evaluate the same checkpoint (iteration
    0). Each policy is drawn once, its legend label the steps in k (not "0M" twice); the titles
    say what is drawn, on which robot; des_vel's limit lines are the runs' configured motor
    limit."""
    from cpg_actor_studies.hopper_paper import figures

    out = tmp_path / "out"
    for variant in ("cpg-actor", "mlp"):
        run = _fake_run(out, variant, 0)
        rows = [{"iteration": i, "global_step": 2048 * i} for i in range(3)]
        (run / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
        stages = [{"stage": k, "fraction": f, "iteration": i, "checkpoint": "x",
                   "traces": "eval/stage0/traces.npz"}
                  for k, (f, i) in enumerate(((1 / 60, 0), (1 / 3, 0), (1.0, 2)))]  # fmt: skip
        (run / "eval" / "stages.json").write_text(json.dumps(stages))
        (run / "config.yaml").write_text("robot: hopper\nenv:\n  velocity_limit: 12.0\n")
    drawn = {}

    def keep(fig, directory, name):  # the figure, instead of its files
        drawn[name] = fig
        return []

    monkeypatch.setattr(figures, "_save", keep)
    results = Results.load(out, ["cpg-actor", "mlp"])
    assert figures.cpg_actor_training_over_time(results, out) == ([], [])
    fig = drawn["cpg_actor_training_over_time"]
    heights, hfe, kfe = fig.axes
    assert [t.get_text() for t in hfe.get_legend().get_texts()] == ["0 steps", "4.1k steps"]
    assert [t.get_text() for t in heights.get_legend().get_texts()] == [
        "hip, 0 steps", "hip, 4.1k steps"]  # fmt: skip
    titles = [fig._suptitle.get_text()] + [axis.get_title() for axis in fig.axes]
    assert "progressively" not in " ".join(titles)
    assert titles[0] == (
        "CPG-Actor seed 0 on the hopper: eval episode 0 after 0, 4.1k training steps"
    )
    assert titles[1:] == ["The hopper's hip and foot height at each snapshot",
                          "Desired HFE position at each snapshot",
                          "Desired KFE position at each snapshot"]  # fmt: skip

    figures.des_output(results, out)
    for axis in drawn["des_vel"].axes:
        limits = sorted(line.get_ydata()[0] for line in axis.get_lines()
                        if line.get_linestyle() == "--")  # fmt: skip
        assert limits == [-12.0, 12.0]


def test_the_tables_of_means_say_that_fewer_seeds_show_the_mean_alone(tmp_path):
    out = tmp_path / "out"
    _fake_run(out, "cpg-actor", 0, responsive=True)
    report = write_report(out).read_text()
    assert _interval_free(report) == []
    assert report.count("(n < 3 seeds: the mean alone, no interval)") == 3


def test_a_sweep_of_one_seed_shows_the_value_alone_marked_n_1():
    from cpg_actor_studies.sweep import _mean_std

    assert _mean_std([0.51234], 3) == "0.512 (n=1)"
    assert _mean_std([1.0, float("nan")], 1) == "1.0 (n=1)"
    assert _mean_std([1.0, 3.0], 1) == "2.0 ± 1.0"
    assert _mean_std([], 1) == "-"


def test_stage_steps_are_the_logged_steps_with_a_start_gaits_search_charged(tmp_path):
    """A run charged with its start gait's search begins its step count at the search's steps:
    a stage's steps are those logged at its iteration, not the iteration times the first
    row's steps per iteration."""
    from cpg_actor_studies.hopper_paper.summary import summarise

    out = tmp_path / "out"
    for seed in range(3):
        run = _fake_run(out, "cpg-actor", seed)
        rows = [{"iteration": i, "global_step": 496_000 + 2048 * i} for i in range(8)]
        (run / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    summary = summarise(Results.load(out, ["cpg-actor"]), total_steps=510_336)
    assert [stage["steps"] for stage in summary["variants"]["cpg-actor"]["stages"]] == [
        496_000 + 2048 * 5
    ]
