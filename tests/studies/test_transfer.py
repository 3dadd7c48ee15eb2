"""`cpg-actor transfer`: final policies evaluated in both simulators, and the report's table."""

import json

import numpy as np
import pytest

from cpg_actor import statistics as st
from cpg_actor.cli import main
from cpg_actor_studies.reproduction.execute import MARKER
from cpg_actor_studies.reproduction.plan import ReproduceSettings, write_settings_file
from cpg_actor_studies.transfer import kept, transfer_lines
from tiny import trained_run  # tests/tiny.py (pytest puts tests/ on sys.path)


def test_transfer_evaluates_each_run_in_both_simulators(tmp_path, capsys):
    out = tmp_path / "out"
    for seed in (0, 1):
        run_dir = out / "runs" / "cpg-actor" / f"seed{seed}"
        trained_run(run_dir, "cpg-actor", seed=seed)
    assert main(["transfer", str(out), "--episodes", "2"]) == 0
    data = json.loads((out / "transfer.json").read_text())
    runs = data["runs"]["cpg-actor"]
    assert set(runs) == {"0", "1"}
    for values in runs.values():
        assert values["trained_in"] == "mujoco"
        assert np.isfinite(values["mujoco"]["return"]) and np.isfinite(values["pybullet"]["return"])
    assert "## Cross-simulator transfer" in (out / "report.md").read_text()
    assert main(["transfer", str(out)]) == 2  # refuses to replace transfer.json
    assert "pass --overwrite" in capsys.readouterr().err


def test_transfer_add_keeps_earlier_runs_and_evaluates_only_new_finished_ones(tmp_path, capsys):
    out = tmp_path / "out"
    settings = ReproduceSettings(variants=["mlp"], seeds=3, total_steps=4096)
    write_settings_file(out, settings, "cpg-actor reproduce ...", {})

    def finished_run(seed):
        run_dir = trained_run(out / "runs" / "mlp" / f"seed{seed}", "mlp", seed=seed)
        (run_dir / MARKER).write_text(json.dumps({"status": "done"}))

    finished_run(0)
    trained_run(out / "runs" / "mlp" / "seed2", "mlp", seed=2)  # still training: no marker
    assert main(["transfer", str(out), "--episodes", "2"]) == 0
    assert "mlp/seed2 skipped (not finished)" in capsys.readouterr().out
    first = json.loads((out / "transfer.json").read_text())["runs"]["mlp"]
    assert set(first) == {"0"}
    # a later sitting: seed 0 kept its logs but not its checkpoints, seed 1 is new
    for path in (out / "runs" / "mlp" / "seed0" / "checkpoints").iterdir():
        path.unlink()
    finished_run(1)
    assert main(["transfer", str(out), "--episodes", "3", "--add"]) == 2
    assert "--add needs the same" in capsys.readouterr().err
    assert main(["transfer", str(out), "--episodes", "2", "--add"]) == 0
    runs = json.loads((out / "transfer.json").read_text())["runs"]["mlp"]
    assert set(runs) == {"0", "1"} and runs["0"] == first["0"]
    assert np.isfinite(runs["1"]["pybullet"]["return"])
    # without --add the run without a checkpoint would be dropped
    assert main(["transfer", str(out), "--episodes", "2", "--overwrite"]) == 0
    assert set(json.loads((out / "transfer.json").read_text())["runs"]["mlp"]) == {"1"}


def test_kept_share_is_other_over_own_with_a_paired_interval():
    data = {"episodes": 5, "seed": 1000, "runs": {"mlp": {
        str(s): {"trained_in": "mujoco", "mujoco": {"return": 100.0 * (s + 1), "hop_height": 0.3},
                 "pybullet": {"return": 90.0 * (s + 1), "hop_height": 0.15}}
        for s in range(3)}}}  # fmt: skip
    row = kept(data)["mlp"]
    assert row["return_kept"].estimate == pytest.approx(0.9)
    # paired: every seed keeps exactly 90 %, so the interval has no width
    assert row["return_kept"].low == pytest.approx(0.9) == row["return_kept"].high
    assert row["hop_height_kept"].estimate == pytest.approx(0.5)
    assert st.bootstrap_ratio([90.0, 180.0, 270.0], [100.0, 200.0, 300.0]).low < 0.9
    assert "| `mlp` | mujoco | 3 | 200 | 180 | 90% [90, 90] |" in "\n".join(transfer_lines(data))


def test_the_report_and_transfer_are_the_hoppers(tmp_path):
    """The reproduction report tests the paper's claims on the hopper and says so for other
    robots' runs; transfer needs a robot that runs in both simulators. The tables name the
    robot's headline metric (its Robot entry's first)."""
    from cpg_actor.robots.registry import get_robot
    from cpg_actor_studies.hopper_paper.summary import check_hopper_runs
    from cpg_actor_studies.reproduction.results import Results
    from cpg_actor_studies.transfer import evaluate_run

    run_dir = tmp_path / "runs" / "mlp" / "seed0"
    run_dir.mkdir(parents=True)
    (run_dir / "config.yaml").write_text("robot: go1\n")
    with pytest.raises(ValueError, match="report is the paper's, on the hopper; .* on go1"):
        check_hopper_runs(Results.load(tmp_path))
    with pytest.raises(ValueError, match="transfer evaluates in mujoco and pybullet: the go1"):
        evaluate_run(run_dir, 1, 0)
    assert get_robot("hopper").headline_metric == "hop_height"
    assert get_robot("go1").headline_metric == "speed_error"
    data = {"episodes": 1, "seed": 0, "metric": "speed_error", "runs": {"mlp": {"0": {
        "trained_in": "mujoco", "mujoco": {"return": 10.0, "speed_error": 0.2},
        "pybullet": {"return": 5.0, "speed_error": 0.4}}}}}  # fmt: skip
    assert "forward-speed error own (m/s) |" in "\n".join(transfer_lines(data))
