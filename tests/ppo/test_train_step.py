"""The fused PPO step (``ppo.compile``): the loss, its gradient, the clip and Adam in one
compiled function update the agent as the separate calls do, to float32 rounding."""

import pytest
import torch

from cpg_actor.ppo import train_step
from cpg_actor.ppo.algorithm import NonFiniteLossError, cpp_compiler

from .fake_env import fake_runner

pytestmark = pytest.mark.skipif(
    cpp_compiler() is None, reason="torch.compile's CPU backend needs a C++ compiler"
)


@pytest.mark.parametrize(
    "agent, schedule, cpg_schedule, desired_kl",
    [
        ("cpg-actor", "adaptive", "fixed", 0.01),
        ("cpg-actor", "adaptive", "follow", 1e-12),  # the rate falls, the CPG's with it
        ("mlp", "linear", "", 0.01),
    ],
)
def test_the_fused_step_updates_as_the_separate_calls(agent, schedule, cpg_schedule, desired_kl):
    """Two updates (12 steps; the CPG-Actor's CPG in an Adam group of its own, at its own
    rate): parameters, Adam moments, statistics and the adaptive learning rate as with the
    compiled loss, autograd, the clip and the fused Adam kernel, within float32 rounding of
    how far the update moved."""
    cpg_rate = {"cpg_learning_rate": 3e-3, "cpg_lr_schedule": cpg_schedule} if cpg_schedule else {}

    def run(fused: bool):
        runner = fake_runner(
            agent, compile=True, learning_rate=1e-3, lr_schedule=schedule, fused_step=fused,
            desired_kl=desired_kl, **cpg_rate,
        )  # fmt: skip
        assert (runner.ppo.fused_step is not None) == fused
        start = {k: v.clone() for k, v in runner.agent.state_dict().items()}
        stats = []
        for _ in range(2):
            runner.collect()
            stats.append(runner.ppo.update(runner.storage))
        return runner, start, stats

    fused, start, fused_stats = run(True)  # one after the other: a runner seeds torch
    separate, _, separate_stats = run(False)
    theirs = separate.agent.state_dict()
    for name, value in fused.agent.state_dict().items():
        moved = (theirs[name] - start[name]).abs().max()
        if moved > 0:
            assert (value - theirs[name]).abs().max() <= 1e-3 * moved + 1e-7, name
    for a, b in zip(fused_stats, separate_stats, strict=True):
        assert a["num_minibatch_updates"] == b["num_minibatch_updates"] == 6
        assert a["learning_rate"] == pytest.approx(b["learning_rate"], rel=1e-12)
        if schedule == "adaptive":  # the rule acted (up by 1.5, or down with a tiny target)
            assert a["learning_rate"] != 1e-3
        if cpg_schedule == "fixed" or (cpg_schedule and a["learning_rate"] > 1e-3):
            assert a["cpg_learning_rate"] == b["cpg_learning_rate"] == 3e-3
        elif cpg_schedule:  # follows the others' rate down
            assert a["cpg_learning_rate"] == pytest.approx(b["cpg_learning_rate"], rel=1e-12)
            assert a["cpg_learning_rate"] == pytest.approx(3 * a["learning_rate"], rel=1e-12)
        for key in ("policy_loss", "value_loss", "entropy"):
            assert a[key] == pytest.approx(b[key], rel=1e-3, abs=1e-6), key
    ours, theirs = fused.ppo.optimizer.state_dict(), separate.ppo.optimizer.state_dict()
    assert ours["param_groups"] == theirs["param_groups"]
    for index, state in theirs["state"].items():
        assert torch.equal(ours["state"][index]["step"], state["step"])  # 12 steps
        for key in ("exp_avg", "exp_avg_sq"):
            scale = state[key].abs().max().item()
            torch.testing.assert_close(ours["state"][index][key], state[key], rtol=1e-3,
                                       atol=1e-4 * scale)  # fmt: skip


def test_the_fused_step_is_used_only_where_it_computes_the_same_algorithm():
    assert fake_runner("mlp", compile=False).ppo.fused_step is None
    assert fake_runner("mlp", compile=True, fused_step=False).ppo.fused_step is None
    runner = fake_runner("mlp", compile=True)
    assert train_step.usable(runner.ppo.optimizer)
    decayed = torch.optim.Adam(runner.agent.parameters(), weight_decay=0.1)
    assert not train_step.usable(decayed)


def test_a_non_finite_fused_step_undoes_the_update():
    runner = fake_runner("cpg-actor", compile=True)
    runner.collect()
    before = {k: v.clone() for k, v in runner.agent.state_dict().items()}
    runner.storage.advantages[3, 1] = float("nan")
    with pytest.raises(NonFiniteLossError, match="non-finite PPO loss"):
        runner.ppo.update(runner.storage)
    for name, value in runner.agent.state_dict().items():
        assert torch.equal(value, before[name]), name
