"""The desired positions' signals (cpg_actor.metrics.signals) on constructed data."""

import math

import numpy as np
import pytest

from cpg_actor.metrics import signals


def test_smoothness_is_zero_for_a_line_and_large_for_bang_bang():
    t = np.arange(100, dtype=float)
    line = np.stack([0.01 * t, -0.02 * t], axis=1)[:, None, :]  # (T, E=1, joints=2)
    assert signals.smoothness(line) == pytest.approx(0.0, abs=1e-20)
    bang = 0.5 * (-1.0) ** t  # +-A every step: second difference 4A
    assert signals.smoothness(bang) == pytest.approx(16 * 0.25)
    # a slow sine of amplitude A and period n: about A^2 (2 pi / n)^4 / 2
    amplitude, period = 0.3, 50
    sine = amplitude * np.sin(2 * np.pi * np.arange(5000) / period)
    expected = amplitude**2 * (2 * np.pi / period) ** 4 / 2
    assert signals.smoothness(sine) == pytest.approx(expected, rel=0.01)
    assert signals.smoothness(sine) * 1e4 < signals.smoothness(bang)


def test_smoothness_ignores_nan_after_an_episode_ends():
    p = np.zeros((10, 2, 2))
    p[5:, 1] = np.nan  # episode 1 ended after 5 steps
    p[:, 0, 0] = np.arange(10) ** 2  # second difference 2 everywhere
    value = signals.smoothness(p)
    # episode 0: 8 second differences per joint (4 and 0); episode 1: 3 per joint (0)
    assert value == pytest.approx(8 * 4 / (8 * 2 + 3 * 2))
    assert math.isnan(signals.smoothness(np.zeros((2, 1, 2))))


def test_velocity_share_and_p99():
    v = np.array([0.0, 10.0, -15.0, 15.0, 16.0, -30.0, np.nan, np.nan])
    assert signals.velocity_share(v, 15.0) == pytest.approx(4 / 6)
    assert signals.velocity_share(v, limit=20.0) == pytest.approx(5 / 6)
    assert signals.velocity_p99(np.linspace(-10, 10, 10001)) == pytest.approx(9.9, abs=1e-3)
    assert math.isnan(signals.velocity_share(np.full(3, np.nan), 15.0))


def test_desired_velocity_is_the_finite_difference_of_the_sent_positions():
    # two steps of one env, two joints, by hand: (p[t] - p[t-1]) / dt, the first step NaN
    p = np.array([[[0.40, -0.80]], [[0.45, -0.90]], [[0.45, -0.70]]])  # (T=3, E=1, J=2)
    v = signals.desired_velocity(p, dt=0.01)
    assert v.shape == p.shape and np.isnan(v[0]).all()
    assert v[1, 0] == pytest.approx([5.0, -10.0]) and v[2, 0] == pytest.approx([0.0, 20.0])
    # after an episode ends (NaN rows) the differences are NaN too, and left out of p99
    ended = np.concatenate([p, np.full((2, 1, 2), np.nan)])
    assert np.isnan(signals.desired_velocity(ended, 0.01)[3:]).all()
    assert signals.velocity_p99(signals.desired_velocity(ended, 0.01)) == pytest.approx(
        np.percentile([5.0, 10.0, 0.0, 20.0], 99)
    )
    with pytest.raises(ValueError, match="dt"):
        signals.desired_velocity(p, 0.0)


def test_time_at_a_joint_stop_by_hand():
    low, high = (-0.5, -1.7), (1.3, 0.1)
    p = np.array(
        [
            [[0.4, -0.8], [1.3, -0.8]],  # env 1 at the HFE upper stop
            [[-0.5 + 5e-4, -0.8], [0.4, 0.1]],  # env 0 within the tolerance, env 1 KFE stop
            [[0.4, -1.69], [np.nan, np.nan]],  # 0.01 rad from the KFE stop: not at it; ended
            [[1.3, 0.1], [np.nan, np.nan]],  # both joints at a stop: one step
        ]
    )
    # 6 steps with data (4 steps x 2 envs, 2 after env 1 ended), 4 at a stop
    assert signals.joint_stop_share(p, low, high) == pytest.approx(4 / 6)
    assert signals.joint_stop_share(p, low, high, tolerance=0.02) == pytest.approx(5 / 6)
    assert math.isnan(signals.joint_stop_share(np.full((3, 1, 2), np.nan), low, high))
    with pytest.raises(ValueError, match="one limit per joint"):
        signals.joint_stop_share(p, (0.0,), (1.0,))
