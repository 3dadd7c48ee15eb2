"""`cpg-actor gradient`: the truncated CPG gradient against the full-trajectory one."""

import json

import pytest

from cpg_actor.cli import main
from cpg_actor.robots.common.torch_env import TorchVectorEnv
from cpg_actor.robots.hopper.vector import HopperVectorEnv
from cpg_actor_studies.commands.gradient import build_policy
from cpg_actor_studies.gradient import collect_rollout, truncation_study


def test_a_window_as_long_as_the_rollout_is_the_full_gradient_and_one_step_is_a_sliver():
    policy, config = build_policy(None, seed=0)
    env = TorchVectorEnv(HopperVectorEnv(2, config.env))
    rollout = collect_rollout(policy, env, 40, seed=0, gamma=0.99)
    env.close()
    result = truncation_study(policy.agent, rollout, [1, 40])
    groups = ("log_nu", "log_rho", "log_a", "w", "phi", "feedback")
    for group in groups:
        assert result["full"][f"norm/{group}"] > 0
        assert result["k=40"][f"cos/{group}"] == pytest.approx(1.0, abs=1e-4)
        assert result["k=40"][f"norm/{group}"] == pytest.approx(1.0, abs=1e-4)
        # the paper's one step keeps a few per cent of the gradient's size (finding 2)
        assert result["k=1"][f"norm/{group}"] < 0.2


def test_command_writes_its_table_and_refuses_to_clobber(tmp_path, capsys):
    out = tmp_path / "gradient.md"
    args = ["gradient", "--envs", "2", "--steps", "20", "--ks", "1,4", "--out", str(out)]
    assert main(args) == 0
    text = out.read_text()
    assert "| k=1 |" in text and "| k=4 |" in text and "cpg-actor gradient" in text
    data = json.loads(out.with_suffix(".json").read_text())
    assert set(data["result"]) == {"full", "k=1", "k=4"}
    assert main(args) == 2
    assert "exists; pass --overwrite" in capsys.readouterr().err
    assert main(["gradient", "--ks", "0,2", "--steps", "20"]) == 2
    assert main(["gradient", "--run", str(tmp_path / "nothing")]) == 2
