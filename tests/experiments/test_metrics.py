"""Report metrics and claim verdicts on constructed data; stage checkpoint choice; planning."""

import math

import numpy as np
import pytest

from cpg_actor.experiments import metrics as m
from cpg_actor.experiments.execute import select_stage_checkpoints
from cpg_actor.experiments.plan import (
    ReproduceSettings,
    build_tasks,
    checkpoint_interval,
    parse_variants,
    prepare_out_dir,
    resolve_config,
    write_settings_file,
)


def test_smoothness_is_zero_for_a_line_and_large_for_bang_bang():
    t = np.arange(100, dtype=float)
    line = np.stack([0.01 * t, -0.02 * t], axis=1)[:, None, :]  # (T, E=1, joints=2)
    assert m.smoothness(line) == pytest.approx(0.0, abs=1e-20)
    bang = 0.5 * (-1.0) ** t  # +-A every step: second difference 4A
    assert m.smoothness(bang) == pytest.approx(16 * 0.25)
    # a slow sine of amplitude A and period n: about A^2 (2 pi / n)^4 / 2
    amplitude, period = 0.3, 50
    sine = amplitude * np.sin(2 * np.pi * np.arange(5000) / period)
    expected = amplitude**2 * (2 * np.pi / period) ** 4 / 2
    assert m.smoothness(sine) == pytest.approx(expected, rel=0.01)
    assert m.smoothness(sine) * 1e4 < m.smoothness(bang)


def test_smoothness_ignores_nan_after_an_episode_ends():
    p = np.zeros((10, 2, 2))
    p[5:, 1] = np.nan  # episode 1 ended after 5 steps
    p[:, 0, 0] = np.arange(10) ** 2  # second difference 2 everywhere
    value = m.smoothness(p)
    # episode 0: 8 second differences per joint (4 and 0); episode 1: 3 per joint (0)
    assert value == pytest.approx(8 * 4 / (8 * 2 + 3 * 2))
    assert math.isnan(m.smoothness(np.zeros((2, 1, 2))))


def test_velocity_share_and_p99():
    v = np.array([0.0, 10.0, -15.0, 15.0, 16.0, -30.0, np.nan, np.nan])
    assert m.velocity_share(v) == pytest.approx(4 / 6)
    assert m.velocity_share(v, limit=20.0) == pytest.approx(5 / 6)
    assert m.velocity_p99(np.linspace(-10, 10, 10001)) == pytest.approx(9.9, abs=1e-3)
    assert math.isnan(m.velocity_share(np.full(3, np.nan)))


def test_final_return_uses_the_last_rows_before_the_step():
    steps = [100, 200, 300, 400, 500]
    returns = [None, 1.0, 2.0, 3.0, 4.0]
    assert m.final_return(steps, returns, rows=2) == pytest.approx(3.5)
    assert m.final_return(steps, returns, at_step=300, rows=10) == pytest.approx(1.5)
    assert math.isnan(m.final_return(steps, [None] * 5))


def test_peak_return_is_the_best_moving_mean_and_where_it_ends():
    steps = [10, 20, 30, 40, 50, 60]
    returns = [1.0, 5.0, None, 9.0, 2.0, 1.0]  # None: a row without an evaluation
    peak, at = m.peak_return(steps, returns, rows=2)
    assert peak == pytest.approx(7.0) and at == 40  # mean of 5 and 9 (the None skipped)
    # a run still at its best at the end: the peak is the final return
    assert m.peak_return([1, 2, 3], [1.0, 2.0, 3.0], rows=2) == (2.5, 3.0)
    assert m.peak_return([1], [4.0], rows=10) == (4.0, 1.0)  # fewer rows than the window
    noisy = list(np.random.default_rng(0).normal(size=30))
    rising = [v + i for i, v in enumerate(noisy)]  # best at the end: exactly the final return
    assert m.peak_return(range(30), rising)[0] == m.final_return(range(30), rising)
    assert all(math.isnan(v) for v in m.peak_return([1, 2], [None, float("nan")]))


def test_exploration_std_is_the_mean_std_of_the_logged_log_stds():
    row = {"policy/log_std_0": math.log(0.1), "policy/log_std_1": math.log(0.3), "x": 5.0}
    assert m.exploration_std(row) == pytest.approx(0.2)
    assert math.isnan(m.exploration_std({"charts/SPS": 1.0}))


def test_bootstrap_ratio_and_difference():
    exact = m.bootstrap_ratio([6.0, 6.0, 6.0], [1.0, 1.0, 1.0])
    assert (exact.estimate, exact.low, exact.high) == pytest.approx((6.0, 6.0, 6.0))
    rng = np.random.default_rng(1)
    a = 60 + rng.normal(0, 5, 5)
    b = 10 + rng.normal(0, 1, 5)
    ratio = m.bootstrap_ratio(a, b)
    assert ratio.estimate == pytest.approx(a.mean() / b.mean())
    assert ratio.low < ratio.estimate < ratio.high
    assert 4 < ratio.low and ratio.high < 8
    # wider with fewer seeds
    narrow = m.bootstrap_ratio(a, b)
    wide = m.bootstrap_ratio(a[:2], b[:2])
    assert wide.high - wide.low > 0 and narrow is not None
    assert m.bootstrap_ratio(a, [-1.0, -2.0]) is None  # ratio undefined for negative returns
    assert m.bootstrap_ratio(a, [-1.0, 5.0]) is None  # a resampled mean can be negative
    assert m.bootstrap_ratio([], b) is None
    diff = m.bootstrap_difference(a, b)
    assert diff.estimate == pytest.approx(a.mean() - b.mean())
    assert diff.low > 0
    same = m.bootstrap_difference(b, b + rng.normal(0, 1, 5))
    assert same.low < 0 < same.high


def test_claim_verdicts():
    ok = m.Interval(6.2, 4.0, 8.0)
    assert m.verdict_reward_ratio(ok, ran=True)[0] == m.SUPPORTED
    assert m.verdict_reward_ratio(m.Interval(1.5, 1.1, 2.0), ran=True)[0] == m.NOT_SUPPORTED
    assert m.verdict_reward_ratio(m.Interval(5.0, 0.5, 9.0), ran=True)[0] == m.NOT_SUPPORTED
    assert m.verdict_reward_ratio(None, ran=True)[0] == m.NOT_SUPPORTED
    assert m.verdict_reward_ratio(None, ran=False)[0] == m.NOT_TESTED

    above, spans = m.Interval(3.0, 1.0, 5.0), m.Interval(1.0, -1.0, 3.0)
    assert m.verdict_better({"cho2019-warm": above}, ran=True)[0] == m.SUPPORTED
    verdict, detail = m.verdict_better({"cho2019-warm": above, "cho2019": spans}, ran=True)
    assert verdict == m.NOT_SUPPORTED and "cho2019" in detail
    assert m.verdict_better({}, ran=False)[0] == m.NOT_TESTED

    assert m.verdict_smooth(1e-5, 1e-2)[0] == m.SUPPORTED
    assert m.verdict_smooth(1e-3, 2e-3)[0] == m.NOT_SUPPORTED
    assert m.verdict_smooth(float("nan"), 1.0)[0] == m.NOT_TESTED

    assert m.verdict_near_limits(14.0, 0.99)[0] == m.SUPPORTED
    assert m.verdict_near_limits(3.0, 1.0)[0] == m.NOT_SUPPORTED  # far below the limit
    assert m.verdict_near_limits(40.0, 0.5)[0] == m.NOT_SUPPORTED  # far above it
    assert m.verdict_near_limits(float("nan"), float("nan"))[0] == m.NOT_TESTED

    doubled = m.bootstrap_ratio([0.22, 0.24, 0.2], [0.1, 0.11, 0.12])
    flat = m.bootstrap_ratio([0.3, 0.2, 0.25], [0.2, 0.22, 0.24])
    assert m.verdict_hop_doubles(doubled, 1e6, 2e6)[0] == m.SUPPORTED
    assert m.verdict_hop_doubles(flat, 1e6, 20e6)[0] == m.NOT_SUPPORTED
    assert m.verdict_hop_doubles(doubled, 1e6, 1.5e6)[0] == m.NOT_TESTED  # too short a run
    assert m.verdict_hop_doubles(None, 1e6, 2e6)[0] == m.NOT_TESTED

    above = {"mlp": m.bootstrap_difference([5.0, 6.0, 7.0], [1.0, 2.0, 1.5])}
    mixed = dict(above, cho=m.bootstrap_difference([5.0, 6.0, 7.0], [8.0, 9.0, 8.5]))
    assert m.verdict_best_during_training(above, ran=True)[0] == m.SUPPORTED
    assert m.verdict_best_during_training(mixed, ran=True)[0] == m.NOT_SUPPORTED
    assert m.verdict_best_during_training({}, ran=True)[0] == m.NOT_TESTED


def test_stage_checkpoints_are_the_nearest():
    checkpoints = {i: f"iter_{i:06d}.pt" for i in (0, 40, 80, 120, 160, 200, 240)}
    chosen = select_stage_checkpoints(checkpoints, 240, (1 / 60, 1 / 3, 1.0))
    assert [iteration for _, iteration, _ in chosen] == [0, 80, 240]
    chosen = select_stage_checkpoints({0: "a", 2: "b"}, 2, (1 / 60, 1 / 3, 1.0))
    assert [iteration for _, iteration, _ in chosen] == [0, 0, 2]
    with pytest.raises(ValueError):
        select_stage_checkpoints({}, 10, (1.0,))


def test_checkpoint_interval_is_dense_but_keeps_whole_episodes():
    settings = ReproduceSettings(variants=["cpg-actor"], seeds=1, total_steps=20_000_000)
    config = resolve_config(settings, "cpg-actor")
    interval = checkpoint_interval(config)  # 9766 iterations of 64 x 32 steps
    assert interval == config.num_iterations // 240
    assert interval * config.ppo.num_steps >= 2 * config.env.episode_steps
    # the 1M-step stage of a 60M run lies within one interval of a checkpoint
    assert interval <= config.num_iterations / 60 / 4
    short = resolve_config(ReproduceSettings(variants=["mlp"], seeds=1, total_steps=100_000), "mlp")
    assert checkpoint_interval(short) * short.ppo.num_steps >= 2 * short.env.episode_steps


def test_variants_are_checked_against_the_registry():
    assert parse_variants("cpg-actor, mlp") == ["cpg-actor", "mlp"]
    with pytest.raises(ValueError, match="available: .*cpg-actor"):
        parse_variants("cpg-actor,nope")
    with pytest.raises(ValueError, match="twice"):
        parse_variants("mlp,mlp")


def test_a_variant_is_an_agent_with_settings_of_its_own(tmp_path):
    """cpg-actor-unbounded trains cpg-actor with the paper's linear feedback; the
    reproduction's own --set still wins over the variant's settings."""
    assert parse_variants("cpg-actor-unbounded") == ["cpg-actor-unbounded"]
    settings = ReproduceSettings(
        variants=["cpg-actor-unbounded"], seeds=1, total_steps=4096,
        overrides=["agent_config.kappa_scale=2.0"],
    )  # fmt: skip
    config = resolve_config(settings, "cpg-actor-unbounded")
    assert config.agent == "cpg-actor" and config.agent_config.feedback_tanh is False
    assert (config.agent_config.xi_scale, config.agent_config.kappa_scale) == (1.0, 2.0)
    (task,) = build_tasks(settings, tmp_path, workers=1)
    args = list(task.train_args)
    assert args[args.index("--agent") + 1] == "cpg-actor"
    assert args.index("agent_config.feedback_tanh=false") < args.index(
        "agent_config.kappa_scale=2.0"
    )
    assert task.run_dir.endswith("runs/cpg-actor-unbounded/seed0")


def test_out_dir_with_other_settings_is_refused(tmp_path):
    out = tmp_path / "out"
    settings = ReproduceSettings(variants=["mlp"], seeds=2, total_steps=1000)
    assert prepare_out_dir(out, settings, overwrite=False) == "new"
    write_settings_file(out, settings, "cpg-actor reproduce", {"workers": 1})
    assert prepare_out_dir(out, settings, overwrite=False) == "resume"
    other = ReproduceSettings(variants=["mlp"], seeds=2, total_steps=2000)
    with pytest.raises(FileExistsError, match="total_steps: 1000 -> 2000"):
        prepare_out_dir(out, other, overwrite=False)
    # more variants and seeds, all else equal: the finished runs stay valid
    more = ReproduceSettings(variants=["mlp", "cpg-actor"], seeds=4, total_steps=1000)
    assert prepare_out_dir(out, more, overwrite=False) == "extend"
    for fewer in (
        ReproduceSettings(variants=["cpg-actor"], seeds=2, total_steps=1000),
        ReproduceSettings(variants=["mlp"], seeds=1, total_steps=1000),
        ReproduceSettings(variants=["mlp", "cpg-actor"], seeds=4, total_steps=2000),
    ):
        with pytest.raises(FileExistsError, match="other settings"):
            prepare_out_dir(out, fewer, overwrite=False)
    (out / "keep").write_text("x")
    assert prepare_out_dir(out, other, overwrite=True) == "overwrite"
    assert not (out / "keep").exists()
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "data.txt").write_text("x")
    with pytest.raises(FileExistsError, match="not written by"):
        prepare_out_dir(foreign, settings, overwrite=True)


def test_bound_share_counts_feedback_at_its_bound_and_variability_flat_signals():
    from cpg_actor.experiments.metrics import bound_share, variability

    t = np.linspace(0, 5, 500)
    bang_bang = 4.0 * np.tanh(50 * np.sin(2 * np.pi * 2 * t))  # at +-4 nearly always
    smooth = 4.0 * np.tanh(0.5 * np.sin(2 * np.pi * 2 * t))
    assert bound_share(bang_bang, 4.0) > 0.9
    assert bound_share(smooth, 4.0) == 0.0
    flat = np.full((500, 3, 2), 4 * np.pi)
    moving = flat + 2.0 * np.sin(2 * np.pi * t)[:, None, None]
    assert variability(flat) == pytest.approx(0.0, abs=1e-9)
    assert variability(moving) == pytest.approx(2.0 / np.sqrt(2), rel=0.02)
