"""Training on the Go1 (`--robot go1`): the CPG-Actor in both CPG layouts and the MLP train
through the same runner as the other robots, and `cpg-actor train --robot go1` runs from the
command line."""

import json

import pytest
import torch

from cpg_actor.cli import main
from cpg_actor.config import apply_dict
from cpg_actor.robots.go1.vector import Go1VectorEnv
from cpg_actor.runner import Runner
from tiny import tiny_config


@pytest.mark.parametrize(
    "agent, layout", [("cpg-actor", "joint"), ("cpg-actor", "leg"), ("mlp", "")]
)
def test_every_agent_trains_on_the_go1(agent, layout):
    config = tiny_config(agent)
    apply_dict(config, {"robot": "go1", "env": {"episode_seconds": 0.2}}, "")
    if layout:
        apply_dict(config, {"agent_config": {"cpg_layout": layout}}, "")
    runner = Runner(config, tensorboard=False)
    try:
        assert isinstance(runner.env.unwrapped, Go1VectorEnv)
        before = {k: v.clone() for k, v in runner.agent.state_dict().items()}
        runner.learn()
        after = runner.agent.state_dict()
        assert all(torch.isfinite(v).all() for v in after.values())
        assert any(not torch.equal(before[k], after[k]) for k in before)
        if agent == "cpg-actor":
            assert runner.agent.cpg.num_oscillators == (8 if layout == "joint" else 4)
    finally:
        runner.close()


def test_train_from_the_command_line(tmp_path):
    run = tmp_path / "run"
    code = main(["train", "--robot", "go1", "--agent", "cpg-actor", "--total-steps", "64",
                 "--num-envs", "2", "--run-dir", str(run), "--no-progress",
                 "--set", "ppo.num_steps=16", "--set", "ppo.compile=false",
                 "--set", "eval_interval=0", "--set", "env.episode_seconds=0.2"])  # fmt: skip
    assert code in (0, None)
    assert (run / "checkpoints" / "last.pt").exists()
    lines = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    assert lines and "go1" in (run / "config.yaml").read_text()
