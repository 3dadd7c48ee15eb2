"""Training on the Go1 (`--robot go1`): the CPG-Actor in both CPG layouts and the MLP train
through the same runner as the other robots, and `cpg-actor train --robot go1` runs from the
command line."""

import json

import pytest
import torch

from cpg_actor.cli import main
from cpg_actor.config import apply_dict
from cpg_actor.robots.go1.vector import Go1VectorEnv
from cpg_actor.training.runner import Runner
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


def test_a_trained_policy_exports_with_the_go1s_actuators(tmp_path):
    """`cpg-actor export` of a Go1 run: the metadata names the robot and its per-joint
    actuator constants, and the MJCF written next to the policy is the Go1's."""
    from cpg_actor.deploy import load_policy
    from cpg_actor.deploy.export import export_policy, read_metadata, sidecar_paths
    from tiny import trained_run

    run = trained_run(tmp_path / "run", "cpg-actor", "go1", env={"episode_seconds": 0.2})
    path = export_policy(load_policy(run), tmp_path / "policy.pt", "torchscript")
    metadata = read_metadata(path)
    assert metadata["robot"] == "go1" and metadata["robot_model"] == "unitree-go1"
    actuator = metadata["actuator"]
    assert actuator["torque_limit"] == [23.7, 23.7, 35.55]
    assert '<mujoco model="go1">' in sidecar_paths(path)["mjcf"].read_text()
