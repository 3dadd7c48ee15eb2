import torch

from cpg_actor.ppo import compute_gae


def hand_gae(rewards, values, terminated, truncated, final_values, last_value, gamma, lam):
    """Scalar-loop GAE for one environment, written independently of compute_gae."""
    n = len(rewards)
    adv = [0.0] * n
    running = 0.0
    for t in reversed(range(n)):
        if terminated[t]:
            target, cont = rewards[t], 0.0
        elif truncated[t]:
            target, cont = rewards[t] + gamma * final_values[t], 0.0
        else:
            nxt = last_value if t == n - 1 else values[t + 1]
            target, cont = rewards[t] + gamma * nxt, 1.0
        running = target - values[t] + gamma * lam * cont * running
        adv[t] = running
    return adv


def test_gae_matches_hand_computation_with_truncation_and_termination():
    gamma, lam = 0.9, 0.8
    rewards = [1.0, 2.0, 0.5, -1.0, 3.0]
    values = [0.3, 0.1, 0.7, 0.2, -0.4]
    terminated = [0, 0, 0, 1, 0]
    truncated = [0, 1, 0, 0, 0]
    final_values = [0.0, 5.0, 0.0, 9.0, 0.0]  # 9.0 must be ignored: terminated row
    last_value = 2.0
    expected = hand_gae(
        rewards, values, terminated, truncated, final_values, last_value, gamma, lam
    )

    def col(x):
        return torch.tensor(x, dtype=torch.float64)[:, None]

    adv, ret = compute_gae(
        col(rewards),
        col(values),
        col(terminated),
        col(truncated),
        col(final_values),
        torch.tensor([last_value], dtype=torch.float64),
        gamma,
        lam,
    )
    torch.testing.assert_close(adv[:, 0], torch.tensor(expected, dtype=torch.float64))
    torch.testing.assert_close(ret, adv + col(values))
    # explicit numbers for the truncated step: delta_1 = 2 + 0.9 * 5 - 0.1, no carry from t=2
    assert abs(adv[1, 0].item() - (2.0 + 0.9 * 5.0 - 0.1)) < 1e-12
    # terminated step: delta_3 = -1 - 0.2, no bootstrap
    assert abs(adv[3, 0].item() - (-1.0 - 0.2)) < 1e-12


def test_gae_lambda_one_is_discounted_return_minus_value():
    rewards = torch.tensor([[1.0], [1.0], [1.0]], dtype=torch.float64)
    values = torch.zeros(3, 1, dtype=torch.float64)
    zeros = torch.zeros(3, 1, dtype=torch.float64)
    adv, _ = compute_gae(
        rewards, values, zeros, zeros, zeros, torch.tensor([10.0], dtype=torch.float64), 0.5, 1.0
    )
    assert abs(adv[0, 0].item() - (1 + 0.5 + 0.25 + 0.125 * 10)) < 1e-12
