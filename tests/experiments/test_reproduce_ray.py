"""`cpg-actor reproduce --ray local`: one tiny run as a task of a local Ray instance."""

import json

import pytest

from cpg_actor.cli import main

pytest.importorskip("ray")


def test_reproduce_on_a_local_ray_instance(tmp_path, capsys):
    out = tmp_path / "results"
    argv = [
        "reproduce", "--out", str(out), "--ray", "local", "--variants", "mlp", "--seeds", "1",
        "--total-steps", "64", "--num-envs", "4", "--set", "ppo.num_steps=8",
        "--set", "ppo.num_minibatches=2", "--set", "ppo.num_epochs=1",
        "--set", "env.episode_steps=10", "--eval-episodes", "1", "--no-progress",
    ]  # fmt: skip
    assert main(argv) == 0
    assert "Ray at local" in capsys.readouterr().out
    marker = json.loads((out / "runs" / "mlp" / "seed0" / "reproduce_run.json").read_text())
    assert marker["status"] == "done"
    assert (out / "report.md").is_file()
    assert "ray: local" in (out / "reproduce.yaml").read_text()
