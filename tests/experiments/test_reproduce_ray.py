"""`cpg-actor reproduce --ray local`: one tiny run as a task of a local Ray instance."""

import json

import pytest

from cpg_actor.cli import main

pytest.importorskip("ray")


@pytest.mark.slow
def test_reproduce_on_a_local_ray_instance(tmp_path, capsys):
    out = tmp_path / "results"
    argv = [
        "reproduce", "--out", str(out), "--ray", "local", "--variants", "mlp", "--seeds", "1",
        "--total-steps", "64", "--num-envs", "4", "--set", "ppo.num_steps=8",
        "--set", "ppo.num_minibatches=2", "--set", "ppo.num_epochs=1",
        "--set", "env.episode_steps=10", "--eval-episodes", "1", "--no-progress",
        "--set", "ppo.compile=false",
    ]  # fmt: skip
    assert main(argv) == 0
    assert "Ray at local" in capsys.readouterr().out
    marker = json.loads((out / "runs" / "mlp" / "seed0" / "reproduce_run.json").read_text())
    assert marker["status"] == "done"
    assert (out / "report.md").is_file()
    assert "ray: local" in (out / "reproduce.yaml").read_text()


@pytest.mark.slow
def test_each_run_asks_ray_for_its_share_of_a_gpu(tmp_path, capsys, monkeypatch):
    """Two runs of half a GPU each on a local Ray instance that declares 2 (fake) GPUs."""
    from cpg_actor.experiments import execute

    run_ray = execute.run_ray
    monkeypatch.setattr(
        execute, "run_ray", lambda *args, **kwargs: run_ray(*args, **kwargs, local_gpus=2)
    )
    argv = [
        "reproduce", "--out", str(tmp_path / "results"), "--ray", "local", "--gpus-per-run",
        "0.5", "--variants", "mlp", "--seeds", "2", "--total-steps", "32", "--num-envs", "4",
        "--set", "ppo.num_steps=8", "--set", "ppo.num_minibatches=2", "--set",
        "ppo.num_epochs=1", "--set", "env.episode_steps=10", "--eval-episodes", "1",
        "--no-progress", "--set", "ppo.compile=false",
    ]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert out.count("done") >= 2 and out.count("on 0.5 GPU") == 2
    assert "gpus_per_run: 0.5" in (tmp_path / "results" / "reproduce.yaml").read_text()


def test_gpu_shares_need_ray(tmp_path, capsys):
    assert main(["reproduce", "--out", str(tmp_path / "r"), "--gpus-per-run", "0.5"]) != 0
    assert "--gpus-per-run is for --ray" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()
