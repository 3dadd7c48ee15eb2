"""`Policy` (normaliser -> agent -> clip, with per-env CPG state) and `load_policy`."""

import numpy as np
import pytest
import torch

from cpg_actor.deploy import load_policy
from cpg_actor.robots.hopper.vector import HopperVectorEnv
from cpg_actor.training.runner import Runner
from tiny import tiny_config  # tests/tiny.py (pytest puts tests/ on sys.path)


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    run_dir = tmp_path_factory.mktemp("policy") / "run"
    runner = Runner(tiny_config("cpg-actor"), run_dir=run_dir, tensorboard=False)
    runner.learn()
    yield runner, run_dir
    runner.close()


def test_load_policy_acts_as_the_trained_agent(trained):
    runner, run_dir = trained
    policy = load_policy(run_dir)
    assert policy.config.agent == "cpg-actor"
    env = HopperVectorEnv(3)
    obs, _ = env.reset(seed=2)
    policy.reset(3)
    runner.policy.reset(3)
    try:
        for _ in range(20):
            a = policy.act(obs)
            b = runner.policy.act(obs, deterministic=True)
            assert np.array_equal(a.action, b.action)
            assert torch.equal(policy.state, runner.policy.state)
            assert (a.action >= policy.action_low).all() and (a.action <= policy.action_high).all()
            obs, _, terminated, truncated, _ = env.step(a.action)
            policy.end_episodes(terminated | truncated)
            runner.policy.end_episodes(terminated | truncated)
    finally:
        env.close()


def test_end_episodes_restarts_only_the_finished_rows(trained):
    policy = load_policy(trained[1])
    policy.reset(3)
    obs = np.zeros((3, 8), dtype=np.float32)
    obs[:, :2] = [0.4, -0.8]
    policy.act(obs)
    before = policy.state.clone()
    policy.end_episodes(np.array([False, True, False]))
    assert torch.equal(policy.state[[0, 2]], before[[0, 2]])
    assert torch.equal(policy.state[1], policy.agent.initial_state(1)[0])


def test_policy_errors_say_what_is_wrong(trained, tmp_path):
    policy = load_policy(trained[1] / "checkpoints" / "last.pt")
    with pytest.raises(RuntimeError, match="reset"):
        policy.act(np.zeros((1, 8), dtype=np.float32))
    policy.reset(2)
    with pytest.raises(ValueError, match=r"shape \(2, 8\), got \(3, 8\)"):
        policy.act(np.zeros((3, 8), dtype=np.float32))
    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_policy(tmp_path / "nothing.pt")
    (tmp_path / "bad.pt").write_bytes(b"garbage")
    with pytest.raises(ValueError, match="corrupt or not a cpg-actor checkpoint"):
        load_policy(tmp_path / "bad.pt")


def test_compiled_training_step_acts_as_the_eager_one(trained):
    """Policy.compile (ppo.compile): the same sampled actions from the same RNG stream, the
    same CPG states and normaliser statistics (to float rounding), over steps with episode
    ends; the normaliser's sample count included (an in-place write to a 0-dim buffer is
    dropped by torch.compile 2.13, which left the count at 0)."""
    policies = [load_policy(trained[1]), load_policy(trained[1])]
    policies[1].compile()
    env = HopperVectorEnv(4)
    obs, _ = env.reset(seed=5)
    for policy in policies:
        policy.reset(4)
    try:
        for t in range(12):
            steps = []
            for policy in policies:
                torch.manual_seed(t)
                steps.append(policy.act(obs, deterministic=False, update_normalizer=True))
            eager, compiled = steps
            np.testing.assert_allclose(compiled.action, eager.action, atol=1e-5)
            torch.testing.assert_close(compiled.agent.log_prob, eager.agent.log_prob)
            torch.testing.assert_close(compiled.agent.value, eager.agent.value)
            torch.testing.assert_close(policies[1].state, policies[0].state)
            obs, _, terminated, truncated, _ = env.step(eager.action)
            done = terminated | truncated
            done[t % 4] |= t % 5 == 4  # some episodes end
            for policy in policies:
                policy.end_episodes(done)
    finally:
        env.close()
    a, b = (policy.normalizer for policy in policies)
    assert a.count.item() == b.count.item() > 0
    torch.testing.assert_close(b.mean, a.mean)
    torch.testing.assert_close(b.var, a.var)


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
@pytest.mark.parametrize("rows", [3, 4096])  # below and above torch's vectorised fill (16)
def test_the_sampling_off_the_cpu_draws_torch_normals_numbers(dtype, rows):
    """gaussian_sample on a GPU skips torch.normal's check of std (a wait for the device per
    step) and computes what it computes: the same numbers and RNG state, bit for bit (the
    computation checked here on the CPU, where torch.normal itself is used)."""
    from cpg_actor.agents.base import gaussian_sample, scaled_noise

    mean = torch.randn(rows, 13, dtype=dtype)
    std = torch.rand(13, dtype=dtype).expand(rows, 13) + 0.1
    draws, states = [], []
    for draw in (torch.normal, scaled_noise, gaussian_sample):
        torch.manual_seed(7)
        draws.append(draw(mean, std))
        states.append(torch.get_rng_state())
    for got, state in zip(draws[1:], states[1:], strict=True):
        assert got.dtype == dtype and torch.equal(got, draws[0])
        assert torch.equal(state, states[0])
