"""`cpg-actor sweep`: settings parsing, and a tiny sweep end to end (2 settings x 1 seed)."""

import json

import pytest

from cpg_actor.cli import main
from cpg_actor_studies.sweep import build_settings, parse_vary


def test_vary_makes_one_setting_per_value_and_groups_keys():
    one = parse_vary("agent_config.init_std=0.3,3")
    assert [s.label for s in one] == ["init_std=0.3", "init_std=3"]
    assert one[0].overrides == ("agent_config.init_std=0.3",)
    pair = parse_vary("ppo.num_epochs,ppo.num_minibatches=5:4,10:8")
    assert pair[1].overrides == ("ppo.num_epochs=10", "ppo.num_minibatches=8")
    assert [s.label for s in build_settings(["ppo.gamma=0.9"])] == ["default", "gamma=0.9"]
    for bad, message in (
        ("ppo.gamma", "KEY=V1,V2"),
        ("a,b=1:2,3", "has 1 values for 2 keys"),
        ("=1", "names no key"),
    ):
        with pytest.raises(ValueError, match=message):
            parse_vary(bad)
    with pytest.raises(ValueError, match="same label"):
        build_settings(["ppo.gamma=0.9", "ppo.gamma=0.9"])


@pytest.mark.slow
def test_sweep_trains_each_setting_and_summarises_the_evaluations(tmp_path, capsys):
    out = tmp_path / "sweep"
    argv = [
        "sweep", "--out", str(out), "--variants", "mlp", "--seeds", "1", "--total-steps", "64",
        "--vary", "agent_config.init_std=0.3", "--workers", "2", "--no-progress",
        "--set", "num_envs=2", "--set", "ppo.num_steps=16", "--set", "ppo.num_minibatches=2",
        "--set", "ppo.num_epochs=1", "--set", "env.episode_steps=10", "--set", "eval_interval=1",
        "--set", "ppo.compile=false",
    ]  # fmt: skip
    assert main(argv) == 0
    summary = json.loads((out / "sensitivity.json").read_text())
    assert list(summary["settings"]) == ["default", "init_std=0.3"]
    run = summary["settings"]["init_std=0.3"]["variants"]["mlp"]
    assert len(run["return"]) == 1 and run["curves"][0]["steps"] == [0, 32, 64]
    table = (out / "sensitivity.md").read_text()
    assert "| `init_std=0.3` |" in table
    config = (out / "init_std=0.3" / "runs" / "mlp" / "seed0" / "config.yaml").read_text()
    assert "init_std: 0.3" in config
    assert (out / "sensitivity.png").stat().st_size > 0
    # a re-run trains nothing (every run is finished) and rewrites the same summary
    assert main(argv) == 0
    assert json.loads((out / "sensitivity.json").read_text()) == summary
    assert main(["sweep", "--out", str(tmp_path / "none"), "--summary-only"]) == 2


def test_first_seed_tunes_on_seeds_that_are_never_reported(tmp_path):
    out = tmp_path / "tuning"
    argv = [
        "sweep", "--out", str(out), "--variants", "mlp", "--seeds", "1", "--first-seed", "100",
        "--total-steps", "32", "--workers", "1", "--no-progress", "--set", "num_envs=2",
        "--set", "ppo.num_steps=16", "--set", "ppo.num_minibatches=2", "--set",
        "ppo.num_epochs=1", "--set", "env.episode_steps=10", "--set", "eval_interval=1",
        "--set", "ppo.compile=false",
    ]  # fmt: skip
    assert main(argv) == 0
    assert sorted(p.name for p in (out / "default" / "runs" / "mlp").iterdir()) == ["seed100"]
    config = (out / "default" / "runs" / "mlp" / "seed100" / "config.yaml").read_text()
    assert "seed: 100" in config
    summary = json.loads((out / "sensitivity.json").read_text())
    assert len(summary["settings"]["default"]["variants"]["mlp"]["return"]) == 1
    assert main([*argv[:8], "-1", *argv[9:]]) == 2  # --first-seed -1


def test_sweep_writes_only_in_its_own_folder_and_overwrite_deletes_only_its_files(tmp_path, capsys):
    from cpg_actor.files import MARKER
    from cpg_actor_studies import sweep
    from cpg_actor_studies.reproduction import plan

    def tree(folder):
        return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*")
                if p.is_file()}  # fmt: skip

    mine = tmp_path / "mine"
    mine.mkdir()
    for name in ("sensitivity.md", "sensitivity.json", "sensitivity.png"):
        (mine / name).write_text("my own study")
    before = tree(mine)
    argv = [
        "sweep", "--variants", "mlp", "--seeds", "1", "--total-steps", "32", "--workers", "1",
        "--no-progress", "--set", "num_envs=2", "--set", "ppo.num_steps=16",
        "--set", "ppo.num_minibatches=2", "--set", "ppo.num_epochs=1",
        "--set", "eval_interval=0", "--set", "ppo.compile=false",
    ]  # fmt: skip
    for extra in ([], ["--overwrite"], ["--summary-only"]):
        assert main([*argv, "--out", str(mine), *extra]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and str(mine) in err and "Traceback" not in err, err
        assert tree(mine) == before and sorted(p.name for p in mine.iterdir()) == sorted(before)

    # a sweep's own directory: --overwrite deletes what the sweep wrote, and only if that is all
    out = tmp_path / "sweep"
    sweep.prepare_out_dir(out)
    settings = sweep.reproduce_settings(sweep.Setting("default", ()), ["mlp"], 1, 32, [])
    plan.prepare_out_dir(out / "default", settings, overwrite=False)
    plan.write_settings_file(out / "default", settings, "cpg-actor sweep", {})
    (out / "default" / "logs").mkdir()
    (out / "default" / "logs" / "mlp_seed0.log").write_text("log")
    (out / "sensitivity.md").write_text("summary")
    (out / "default" / "notes.txt").write_text("mine")
    assert main([*argv, "--out", str(out), "--overwrite"]) == 2
    assert "did not write (default/notes.txt)" in capsys.readouterr().err
    assert (out / "sensitivity.md").is_file() and (out / "default" / "notes.txt").is_file()
    (out / "default" / "notes.txt").unlink()
    sweep.prepare_out_dir(out, overwrite=True)
    assert [p.name for p in out.iterdir()] == [MARKER]


def _fake_run(run_dir, robot: str, evaluations: list[dict]) -> None:
    run_dir.mkdir(parents=True)
    (run_dir / "config.yaml").write_text(f"robot: {robot}\n")
    rows = [
        {"global_step": 1000 * i, "eval/return": 10.0 + i, **e} for i, e in enumerate(evaluations)
    ]
    (run_dir / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))


def test_the_quadrupeds_omnidirectional_score_is_the_metrics_named(tmp_path):
    """--metrics scores the runs by the episode metrics named (the first one read), e.g. the
    linear velocity error and the falls of the omnidirectional task, not the headline."""
    from cpg_actor_studies import sweep

    settings = build_settings(["agent_config.init_std=1.0"])
    for setting, error in zip(settings, (0.2, 0.1), strict=True):
        _fake_run(tmp_path / setting.label / "runs" / "mlp" / "seed100", "go1",
                  [{"eval/lin_vel_error": 0.5, "eval/fell": 1.0}] +
                  [{"eval/lin_vel_error": error, "eval/fell": 0.0}] * 3)  # fmt: skip
    summary = sweep.summarize(tmp_path, settings, ["mlp"], 1, 100, ["lin_vel_error", "fell"])
    assert summary["metric"] == "lin_vel_error"
    run = summary["settings"]["init_std=1.0"]["variants"]["mlp"]
    assert run["lin_vel_error"] == [pytest.approx(0.1, rel=1e-9)] and run["fell"] == [0.0]
    sweep.write_summary(tmp_path, summary, "cpg-actor sweep ...", 1)
    table = (tmp_path / "sensitivity.md").read_text()
    assert "mlp lin vel error (m/s)" in table
    assert "| `init_std=1.0` | 12 (n=1) | 0.100 (n=1) | 0.000 (n=1) | 3k |" in table
    with pytest.raises(ValueError, match="hop_height not an episode metric of robot 'go1'"):
        sweep.summarize(tmp_path, settings, ["mlp"], 1, 100, ["hop_height"])


def test_an_unknown_metric_is_refused_before_anything_is_written(tmp_path, capsys):
    out = tmp_path / "sweep"
    argv = ["sweep", "--out", str(out), "--variants", "mlp", "--seeds", "1", "--total-steps",
            "32", "--metrics", "lin_vel_error", "--no-progress"]  # fmt: skip
    assert main(argv) == 2
    assert "lin_vel_error not an episode metric of robot 'hopper'" in capsys.readouterr().err
    assert not out.exists()


def test_a_sweep_on_the_go1s_omnidirectional_task(tmp_path):
    """--preset omni with --set robot=go1: each run is the Go1's omnidirectional task."""
    from cpg_actor_studies import sweep
    from cpg_actor_studies.reproduction import plan

    (setting,) = build_settings([])
    settings = sweep.reproduce_settings(setting, ["mlp-field"], 1, 4096, ["robot=go1"], 100,
                                        "omni")  # fmt: skip
    config = plan.resolve_config(settings, "mlp-field", 100)
    assert (config.robot, config.preset, config.env.lateral_range) == ("go1", "omni", (-0.5, 0.5))
    (task,) = plan.build_tasks(settings, tmp_path / "default", 1)
    assert task.train_args[task.train_args.index("--preset") + 1] == "omni"
    assert "robot=go1" in task.train_args
