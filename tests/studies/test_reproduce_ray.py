"""`cpg-actor reproduce --ray local`: tiny runs as tasks of a local Ray instance, written into OUT
or returned to it; an unreachable address. A cluster of two nodes: test_reproduce_ray_cluster."""

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
    assert marker["node"]["files"] == "shared"  # the node sees OUT: the run was written there
    assert not list(out.glob(".ray-probe-*"))
    assert (out / "report.md").is_file()
    assert "ray: local" in (out / "reproduce.yaml").read_text()


@pytest.mark.slow
def test_each_run_asks_ray_for_its_share_of_a_gpu(tmp_path, capsys, monkeypatch):
    """Two runs of half a GPU each on a local Ray instance that declares 2 (fake) GPUs, each
    trained in a temporary directory and returned to OUT as its task's result."""
    from cpg_actor_studies.reproduction import execute

    connect = execute.connect_ray
    monkeypatch.setattr(
        execute, "connect_ray", lambda address, local_gpus=None: connect(address, local_gpus=2)
    )
    argv = [
        "reproduce", "--out", str(tmp_path / "results"), "--ray", "local", "--gpus-per-run",
        "0.5", "--ray-results", "return", "--variants", "mlp", "--seeds", "2", "--total-steps",
        "32", "--num-envs", "4", "--set", "ppo.num_steps=8", "--set", "ppo.num_minibatches=2",
        "--set", "ppo.num_epochs=1", "--set", "env.episode_steps=10", "--eval-episodes", "1",
        "--no-progress", "--set", "ppo.compile=false",
    ]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert out.count("done") >= 2 and out.count("on 0.5 GPU") == 2
    assert "gpus_per_run: 0.5" in (tmp_path / "results" / "reproduce.yaml").read_text()
    for seed in (0, 1):
        run = tmp_path / "results" / "runs" / "mlp" / f"seed{seed}"
        marker = json.loads((run / "reproduce_run.json").read_text())
        assert marker["status"] == "done" and marker["node"]["files"] == "returned"
        assert (run / "checkpoints" / "last.pt").is_file()
        assert (run / "eval" / "stage0" / "traces.npz").is_file()
        assert not (run / ".lock").exists()
        log = tmp_path / "results" / "logs" / f"mlp_seed{seed}.log"
        assert "$ cpg-actor train" in log.read_text()
    assert "Ray nodes this invocation (1)" in (tmp_path / "results" / "report.md").read_text()


def test_an_unreachable_address_is_one_line_and_writes_nothing(tmp_path, capsys):
    import socket

    with socket.socket() as holder:  # bound, not listening: connections are refused
        holder.bind(("127.0.0.1", 0))
        address = f"127.0.0.1:{holder.getsockname()[1]}"
        argv = ["reproduce", "--out", str(tmp_path / "r"), "--variants", "mlp", "--ray", address]
        assert main(argv) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith(f"cpg-actor reproduce: error: cannot reach the Ray head at {address}")
    assert not (tmp_path / "r").exists()


def test_ray_results_needs_ray(tmp_path, capsys):
    argv = ["reproduce", "--out", str(tmp_path / "r"), "--ray-results", "return"]
    assert main(argv) == 2
    assert "--ray-results is for --ray" in capsys.readouterr().err


def test_gpu_shares_need_ray(tmp_path, capsys):
    assert main(["reproduce", "--out", str(tmp_path / "r"), "--gpus-per-run", "0.5"]) != 0
    assert "--gpus-per-run is for --ray" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()
