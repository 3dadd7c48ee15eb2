import numpy as np
import torch

from cpg_actor.ppo import RunningNormalizer


def test_running_statistics_equal_population_statistics_of_all_batches():
    torch.manual_seed(0)
    data = torch.randn(1000, 3) * torch.tensor([1.0, 5.0, 0.1]) + torch.tensor([2.0, -3.0, 7.0])
    norm = RunningNormalizer(3)
    for chunk in data.split([1, 10, 300, 89, 600]):
        norm.update(chunk)
    d = data.double()
    torch.testing.assert_close(norm.mean, d.mean(0))
    torch.testing.assert_close(norm.var, d.var(0, unbiased=False))
    assert norm.count.item() == 1000
    y = norm(data)
    assert y.dtype == torch.float32
    torch.testing.assert_close(
        y.double().mean(0), torch.zeros(3, dtype=torch.float64), atol=1e-5, rtol=0
    )
    torch.testing.assert_close(
        y.double().std(0, unbiased=False), torch.ones(3, dtype=torch.float64), atol=1e-4, rtol=0
    )


def test_forward_does_not_update_clips_and_round_trips_state_dict():
    norm = RunningNormalizer(2, clip=3.0)
    norm.update(torch.tensor([[0.0, 0.0], [2.0, 2.0]]))
    before = norm.state_dict()
    out = norm(torch.tensor([[100.0, -100.0]]))
    assert out.tolist() == [[3.0, -3.0]]
    assert norm.count.item() == 2
    other = RunningNormalizer(2, clip=3.0)
    other.load_state_dict(before)
    torch.testing.assert_close(other.mean, norm.mean)
    torch.testing.assert_close(other.var, norm.var)


def test_reward_normalizer_divides_by_the_std_of_discounted_returns_by_hand():
    from cpg_actor.ppo import RewardNormalizer

    gamma = 0.5
    norm = RewardNormalizer(num_envs=2, gamma=gamma)
    rewards = [torch.tensor([1.0, 2.0]), torch.tensor([3.0, -1.0]), torch.tensor([0.5, 4.0])]
    dones = [torch.tensor([a, False]) for a in (False, True, False)]
    returns_seen: list[float] = []
    discounted = [0.0, 0.0]
    for reward, done in zip(rewards, dones, strict=True):
        scaled = norm(reward, done)
        for i in range(2):
            discounted[i] = gamma * discounted[i] + float(reward[i])
        returns_seen += discounted
        std = float(np.sqrt(np.var(returns_seen) + 1e-8))
        np.testing.assert_allclose(scaled.numpy(), reward.numpy() / std, rtol=1e-5)
        for i in range(2):
            if done[i]:
                discounted[i] = 0.0  # the episode ended: its return starts again


def test_reward_normalizer_clips_and_keeps_the_sign_and_resets():
    from cpg_actor.ppo import RewardNormalizer

    norm = RewardNormalizer(num_envs=1, gamma=0.99, clip=0.5)
    for _ in range(50):
        norm(torch.tensor([0.01]), torch.tensor([False]))
    assert float(norm(torch.tensor([5.0]), torch.tensor([False]))) == 0.5
    assert float(norm(torch.tensor([-0.01]), torch.tensor([False]))) < 0
    norm.reset()
    assert float(norm.discounted[0]) == 0.0
    state = norm.state_dict()
    assert set(state) == {"returns_rms.mean", "returns_rms.var", "returns_rms.count"}
