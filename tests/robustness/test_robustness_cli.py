"""`cpg-actor robustness` on tiny trained runs: a reproduction directory grouped by variant,
a lone run, the files, what it refuses; the summary over seeds."""

import json
import math

import numpy as np
import pytest

from cpg_actor.cli import main
from cpg_actor.robustness.summary import markdown, plain, summarise
from tiny import trained_run  # tests/tiny.py (pytest puts tests/ on sys.path)


def test_the_suite_on_a_reproduction_and_a_run(tmp_path, capsys):
    reproduction = tmp_path / "repro"
    short = {"episode_steps": 250}  # the push comes 1-2 s in
    for seed in (0, 1):
        trained_run(reproduction / "runs" / "cpg-actor" / f"seed{seed}", "cpg-actor", seed=seed,
                    env=short)  # fmt: skip
    lone = trained_run(tmp_path / "my-mlp", "mlp", env=short)
    out = tmp_path / "suite"
    args = ["robustness", str(reproduction), str(lone), "--out", str(out), "--episodes", "1",
            "--perturbations", "push_down,payload"]  # fmt: skip
    assert main(args) == 0
    printed = capsys.readouterr().out
    assert "[1/3] cpg-actor seed 0" in printed and "payload 1.7 kg" in printed
    data = json.loads((out / "robustness.json").read_text())
    assert data["perturbations"] == ["push_down", "payload"]
    assert [run["variant"] for run in data["runs"]] == ["cpg-actor", "cpg-actor", "mlp"]
    assert data["variants"]["cpg-actor"]["seeds"] == [0, 1]
    run = data["runs"][0]
    payload = run["perturbations"]["payload"]
    assert [level["level"] for level in payload["levels"]] == [0.34, 0.68, 1.02, 1.7]
    for level in payload["levels"]:
        assert level["retention"] == pytest.approx(level["return"] / run["nominal"]["return"])
        assert "hop_height" in level and "p99_desired_velocity" in level
        assert "torque_rate" in level and "joint_smoothness" in level
    pushes = run["perturbations"]["push_down"]["levels"]
    assert all(len(level["recovery"]) == 1 for level in pushes)
    text = (out / "robustness.md").read_text()
    assert "## push_down" in text and "## payload" in text and "| MLP actor |" in text
    for name in ("push_down", "payload"):
        assert (out / f"robustness_{name}.png").is_file()
    # the suite's files are replaced only when asked
    assert main(args) == 2
    assert "pass --overwrite" in capsys.readouterr().err
    assert main([*args[:-1], "friction"]) == 2  # robustness.json is there
    capsys.readouterr()
    again = ["robustness", str(lone), "--out", str(out), "--episodes", "1", "--perturbations",
             "payload", "--overwrite"]  # fmt: skip
    assert main(again) == 0
    assert json.loads((out / "robustness.json").read_text())["perturbations"] == ["payload"]
    capsys.readouterr()
    assert main(["robustness", str(lone), "--out", str(out), "--perturbations", "wind"]) == 2
    assert "unknown wind; the hopper's are push_up, push_down" in capsys.readouterr().err
    assert main(["robustness", str(tmp_path / "nothing"), "--out", str(out)]) == 2


def test_the_suite_on_a_quadruped(tmp_path):
    run = trained_run(tmp_path / "anymal", "mlp", robot="anymal", env={"episode_seconds": 2.0})
    out = tmp_path / "suite"
    assert main(["robustness", str(run), "--out", str(out), "--episodes", "1",
                 "--perturbations", "push_sideways,latency"]) == 0  # fmt: skip
    data = json.loads((out / "robustness.json").read_text())
    levels = data["runs"][0]["perturbations"]["push_sideways"]["levels"]
    assert [level["level"] for level in levels] == [7.6, 15.2, 30.4, 45.6]
    assert {"speed_error", "fell"} <= set(levels[0])


def test_a_run_trained_with_randomisation_is_evaluated_on_the_nominal_robot(tmp_path, capsys):
    from cpg_actor.config import TrainConfig
    from cpg_actor.deploy import load_policy
    from cpg_actor.robots.common.perturbation import Randomization
    from cpg_actor.robustness.runs import CHECKPOINT, find_runs
    from cpg_actor.robustness.suite import evaluate_run
    from cpg_actor.training.evaluation import evaluate_policy

    ranges = {"payload": [0.0, 1.0], "friction": [0.4, 1.2], "motor_strength": [0.8, 1.2]}
    path = trained_run(tmp_path / "randomized", "mlp", env={"episode_steps": 100,
                                                            "randomize": ranges})  # fmt: skip
    (run,) = find_runs([str(path)])
    result = evaluate_run(run, ["payload"], episodes=2, seed=3, progress=lambda line: None)
    config = TrainConfig.load(path / "config.yaml")
    assert config.env.randomize.active  # the run was trained with its ranges
    config.env = config.env.replace(randomize=Randomization())
    policy = load_policy(path / CHECKPOINT, run_config=config)
    nominal = evaluate_policy(policy, config, 2, seed=3)
    assert result["nominal"]["return"] == pytest.approx(float(np.mean(nominal["episode_return"])),
                                                       rel=1e-6)  # fmt: skip
    assert len(result["perturbations"]["payload"]["levels"]) == 4
    # cpg-actor eval too (legged_gym's play convention); --set puts ranges back
    assert main(["eval", str(path), "--episodes", "2", "--seed", "3"]) == 0
    evaluated = np.load(path / "eval" / "traces.npz")["episode_return"]
    assert np.mean(evaluated) == pytest.approx(result["nominal"]["return"], rel=1e-6)
    assert "evaluated on the nominal robot" in capsys.readouterr().out
    assert main(["eval", str(path), "--episodes", "2", "--seed", "3", "--set",
                 "env.randomize.payload=[2,3]"]) == 0  # fmt: skip
    heavy = np.load(path / "eval" / "traces.npz")["episode_return"]
    assert not np.allclose(heavy, evaluated)


def synthetic_run(seed, retention):
    level = {
        "level": 1.0,
        "return": 100.0 * retention,
        "retention": retention,
        "hop_height": 0.3,
        "p99_desired_velocity": 10.0,
        "recovery": [5.0, "not recovered"],
    }
    return {"variant": "cpg-actor", "seed": seed,
            "nominal": {"return": 100.0, "hop_height": 0.4, "p99_desired_velocity": 9.0},
            "perturbations": {"push_up": {"field": "push", "unit": "N s", "description": "up",
                                          "nominal": 0.0, "levels": [level]}}}  # fmt: skip


def test_the_summary_over_seeds_has_a_ci_from_three_seeds_on():
    two = summarise([synthetic_run(0, 0.8), synthetic_run(1, 0.9)], ("hop_height",))
    entry = two["cpg-actor"]["perturbations"]["push_up"]["levels"][0]
    assert entry["retention"]["estimate"] == pytest.approx(0.85)
    assert math.isnan(entry["retention"]["low"])  # too few seeds for an interval
    assert entry["recovered"]["estimate"] == 0.5 and entry["recovery_steps"]["estimate"] == 5
    three = summarise([synthetic_run(s, r) for s, r in enumerate((0.8, 0.9, 1.0))],
                      ("hop_height",))  # fmt: skip
    entry = three["cpg-actor"]["perturbations"]["push_up"]["levels"][0]
    assert entry["retention"]["low"] <= 0.9 <= entry["retention"]["high"]
    data = {"robot": "hopper", "episodes": 1, "env_seed": 0, "metrics": ["hop_height"],
            "cycle": "hop apex (m)", "variants": three}  # fmt: skip
    assert "| CPG-Actor | 0 (nominal) | 100.0 [100.0, 100.0] | 100% |" in markdown(plain(data))


def test_the_tables_show_the_physical_metrics_a_file_has_and_old_files_none():
    runs = [synthetic_run(s, r) for s, r in enumerate((0.8, 0.9, 1.0))]
    old = summarise(runs, ("hop_height",))
    data = {"robot": "hopper", "episodes": 1, "env_seed": 0, "metrics": ["hop_height"],
            "cycle": "hop apex (m)", "variants": old}  # fmt: skip
    assert "| hop apex (m) |" not in markdown(plain(data))  # written before the metrics
    for run in runs:
        run["nominal"].update(hop_apex=0.5, torque_rate=100.0)
        run["perturbations"]["push_up"]["levels"][0].update(hop_apex=0.25, apex_retention=0.5)
    data["variants"] = summarise(runs, ("hop_height",))
    level = data["variants"]["cpg-actor"]["perturbations"]["push_up"]["levels"][0]
    assert level["apex_retention"]["estimate"] == pytest.approx(0.5)
    text = markdown(plain(data))
    assert "| apex kept | hop apex (m) | torque rate (N m/s) |" in text
    assert "| 50% [50, 50] | 0.25 [0.25, 0.25] | — |" in text  # no torque rate at the level


def test_nominal_env_drops_the_ranges_and_keeps_a_fixed_perturbation():
    from cpg_actor.robots.common.perturbation import Perturbation
    from cpg_actor.robots.hopper.config import HopperConfig
    from cpg_actor.training.evaluation import nominal_env

    plain = HopperConfig()
    assert nominal_env(plain) is plain
    randomized = HopperConfig(randomize={"friction": [0.4, 1.2]},
                              perturbation=Perturbation(push=1.0))  # fmt: skip
    randomized.validate()
    nominal = nominal_env(randomized)
    assert randomized.randomize.active and not nominal.randomize.active
    assert nominal.perturbation.push == 1.0
