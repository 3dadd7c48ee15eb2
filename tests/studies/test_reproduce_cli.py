"""`cpg-actor reproduce` end to end on a tiny budget: 2 variants x 2 seeds on 2 workers, the
run directories, figures and report; a re-run skips finished runs and resumes an unfinished
one; bad input is refused before anything is written. About 2 minutes on 2 cores."""

import json
import shutil
import sys

import pytest

from cpg_actor.cli import main

# 3 iterations of 4 envs x 8 steps, 10-step episodes: episodes finish, evals are short
TINY = [
    "--total-steps", "96", "--num-envs", "4",
    "--set", "ppo.num_steps=8", "--set", "ppo.num_minibatches=2", "--set", "ppo.num_epochs=1",
    "--set", "env.episode_steps=10", "--eval-episodes", "2", "--no-progress",
    "--set", "ppo.compile=false",
]  # fmt: skip


def _checkpoint_times(out):
    return {str(path): path.stat().st_mtime_ns for path in (out / "runs").rglob("checkpoints/*.pt")}


@pytest.mark.slow
def test_reproduce_runs_variants_and_seeds_then_skips_and_resumes(tmp_path, capsys):
    out = tmp_path / "results"
    argv = ["reproduce", *TINY, "--seeds", "2", "--variants", "cpg-actor,mlp"]
    argv += ["--workers", "2", "--out", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "4 runs of 96 steps" in text
    # 3 iterations: the 1/60 stage (iteration 0.05) can only be the untrained agent
    assert "warning: cpg-actor: 3 iterations are too few for the stage(s) at 0.0167" in text
    for variant in ("cpg-actor", "mlp"):
        for seed in (0, 1):
            run = out / "runs" / variant / f"seed{seed}"
            assert (run / "config.yaml").is_file()
            assert (run / "checkpoints" / "last.pt").is_file()
            marker = json.loads((run / "reproduce_run.json").read_text())
            assert marker["status"] == "done" and len(marker["stages"]) == 3
            assert marker["commit"]  # the code that trained it (or "unknown" outside git)
            for k in range(3):
                assert (run / "eval" / f"stage{k}" / "traces.npz").is_file()
    for name in (
        "ep_reward", "cpg_output", "cpg_theta_dot", "cpg_r_dot_dot", "parameters_under_training",
        "cpg_param_training", "mlp_weight_feedback", "mlp_bias_feedback", "des_pos", "des_vel",
        "cpg_actor_training_over_time", "hopper_hip_foot_pos",
    ):  # fmt: skip
        assert (out / "figures" / f"{name}.png").is_file(), name
        assert (out / "figures" / f"{name}.pdf").is_file(), name
    report = (out / "report.md").read_text()
    assert "| CPG-Actor (`cpg-actor`) | 2 (2) |" in report
    assert "not tested in this run" in report  # no Cho et al. variant ran
    assert "cho2019-warm" in report  # and the report says which variants were missing
    settings = (out / "reproduce.yaml").read_text()
    assert "--seeds 2" in settings and "total_steps: 96" in settings
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["variants"]) == {"cpg-actor", "mlp"}

    # the same command again: nothing is trained or evaluated
    before = _checkpoint_times(out)
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert text.count("skipped (finished earlier)") == 4
    assert _checkpoint_times(out) == before

    # an interrupted run: no marker, checkpoints up to iteration 0 -> resumed, the others skipped
    run = out / "runs" / "mlp" / "seed1"
    (run / "reproduce_run.json").unlink()
    for later in (run / "checkpoints").glob("iter_*.pt"):
        if later.name != "iter_000000.pt":
            later.unlink()
    shutil.copyfile(run / "checkpoints" / "iter_000000.pt", run / "checkpoints" / "last.pt")
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "mlp/seed1: done (resumed at iteration 0)" in text
    assert text.count("skipped (finished earlier)") == 3
    assert json.loads((run / "reproduce_run.json").read_text())["status"] == "done"


def test_reproduce_refuses_bad_input_before_writing(tmp_path, capsys):
    out = tmp_path / "r"
    base = ["reproduce", "--out", str(out), "--total-steps", "100"]
    assert main([*base, "--variants", "cpg-actor,nope"]) == 2
    assert "unknown variant(s) nope; available:" in capsys.readouterr().err
    assert main([*base, "--variants", "mlp", "--seeds", "0"]) == 2
    assert "--seeds must be an integer from 1 to 10,000" in capsys.readouterr().err
    assert main(["reproduce", "--out", str(out), "--total-steps", "0", "--variants", "mlp"]) == 2
    assert "positive" in capsys.readouterr().err
    assert main([*base, "--variants", "mlp", "--set", "ppo.no_such_key=1"]) == 2
    assert "unknown config key" in capsys.readouterr().err
    assert not out.exists()
    # an existing reproduction with other settings is kept unless --overwrite
    out.mkdir()
    (out / "reproduce.yaml").write_text(
        "command: x\nsettings: {variants: [mlp], seeds: 3, total_steps: 100}\n"
    )
    assert main([*base, "--variants", "mlp"]) == 2
    assert "other settings" in capsys.readouterr().err


def test_ray_missing_gives_install_hint(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` fails as if not installed
    argv = ["reproduce", "--out", str(tmp_path / "r"), "--variants", "mlp", "--ray", "auto"]
    assert main(argv) == 2
    assert "pip install cpg-actor[ray]" in capsys.readouterr().err


def test_a_preset_reaches_every_run_and_the_settings_file(tmp_path):
    from cpg_actor_studies.reproduction import plan

    settings = plan.ReproduceSettings(
        variants=["mlp"], seeds=2, total_steps=1000, num_envs=8, preset="gpu"
    )
    tasks = plan.build_tasks(settings, tmp_path, workers=1)
    assert [t.train_args[t.train_args.index("--preset") + 1] for t in tasks] == ["gpu", "gpu"]
    config = plan.resolve_config(settings, "mlp")
    assert (config.preset, config.env.sim, config.num_envs) == ("gpu", "mjx", 8)
    out = tmp_path / "out"
    assert plan.prepare_out_dir(out, settings, overwrite=False) == "new"
    plan.write_settings_file(out, settings, "cpg-actor reproduce ...", {})
    assert plan.settings_from_file(out) == settings
    # directories made without a preset keep their identity
    plain = plan.ReproduceSettings(variants=["mlp"], seeds=1, total_steps=10)
    assert "preset" not in plain.identity()


def test_runs_start_seed_by_seed_so_a_stopped_reproduction_has_whole_pairs(tmp_path):
    from cpg_actor_studies.reproduction import plan

    settings = plan.ReproduceSettings(
        variants=["cpg-actor", "cho2019-warm"], seeds=2, total_steps=1000, num_envs=8
    )
    tasks = plan.build_tasks(settings, tmp_path, workers=2)
    assert [t.name for t in tasks] == [
        "cpg-actor/seed0", "cho2019-warm/seed0", "cpg-actor/seed1", "cho2019-warm/seed1",
    ]  # fmt: skip


def test_each_worker_gets_its_share_of_the_cores(tmp_path, monkeypatch):
    """The runs of ``--workers K`` split the cores: their automatic threads (every core each)
    made two runs on 2 cores train 12x slower together (benchmarks/results/shared_device.md)."""
    from cpg_actor_studies.reproduction import plan

    monkeypatch.setattr(plan, "usable_cores", lambda: 8)
    shares = [plan.thread_shares(k)["update_threads"] for k in (1, 2, 3, 8, 16)]
    assert shares == [8, 4, 2, 1, 1]
    assert plan.thread_shares(2) == {"torch_threads": 1, "env_threads": 4, "update_threads": 4}
    settings = plan.ReproduceSettings(variants=["mlp"], seeds=1, total_steps=1000, num_envs=8)
    (task,) = plan.build_tasks(settings, tmp_path, workers=4)
    sets = [task.train_args[i + 1] for i, a in enumerate(task.train_args) if a == "--set"]
    assert {"torch_threads=1", "env_threads=2", "update_threads=2"} <= set(sets)
    # a --set of the user's wins: no share is added for that key
    mine = plan.ReproduceSettings(
        variants=["mlp"], seeds=1, total_steps=1000, num_envs=8, overrides=["update_threads=3"]
    )
    (task,) = plan.build_tasks(mine, tmp_path, workers=4)
    sets = [task.train_args[i + 1] for i, a in enumerate(task.train_args) if a == "--set"]
    assert "update_threads=2" not in sets and "update_threads=3" in sets


@pytest.mark.slow
def test_a_quadruped_reproduction_ends_cleanly_without_the_hoppers_report(tmp_path, capsys):
    """On the Go1 (the omni task, the field's MLP) the runs train and are evaluated at their
    stages; the hopper's report and open-loop floor are not attempted, and the command ends
    with 0."""
    out = tmp_path / "go1"
    argv = ["reproduce", "--set", "robot=go1", *TINY, "--seeds", "1",
            "--variants", "mlp-field", "--preset", "omni",
            "--workers", "1", "--out", str(out)]  # fmt: skip
    argv = [a.replace("env.episode_steps=10", "env.episode_seconds=0.2") for a in argv]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "the report and its claims are the paper's hopper's" in text
    marker = json.loads((out / "runs" / "mlp-field" / "seed0" / "reproduce_run.json").read_text())
    assert marker["status"] == "done"
    assert not (out / "report.md").exists()
