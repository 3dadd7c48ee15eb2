"""Report metrics and claim verdicts on constructed data; stage checkpoint choice; planning."""

import math

import numpy as np
import pytest

from cpg_actor import statistics as st
from cpg_actor_studies.hopper_paper import claims as paper
from cpg_actor_studies.reproduction import numbers
from cpg_actor_studies.reproduction.execute import select_stage_checkpoints
from cpg_actor_studies.reproduction.plan import (
    ReproduceSettings,
    build_tasks,
    checkpoint_interval,
    parse_variants,
    prepare_out_dir,
    resolve_config,
    write_settings_file,
)


def test_final_return_uses_the_last_rows_before_the_step():
    steps = [100, 200, 300, 400, 500]
    returns = [None, 1.0, 2.0, 3.0, 4.0]
    assert numbers.final_return(steps, returns, rows=2) == pytest.approx(3.5)
    assert numbers.final_return(steps, returns, at_step=300, rows=10) == pytest.approx(1.5)
    assert math.isnan(numbers.final_return(steps, [None] * 5))


def test_peak_return_is_the_best_moving_mean_and_where_it_ends():
    steps = [10, 20, 30, 40, 50, 60]
    returns = [1.0, 5.0, None, 9.0, 2.0, 1.0]  # None: a row without an evaluation
    peak, at = numbers.peak_return(steps, returns, rows=2)
    assert peak == pytest.approx(7.0) and at == 40  # mean of 5 and 9 (the None skipped)
    # a run still at its best at the end: the peak is the final return
    assert numbers.peak_return([1, 2, 3], [1.0, 2.0, 3.0], rows=2) == (2.5, 3.0)
    assert numbers.peak_return([1], [4.0], rows=10) == (4.0, 1.0)  # fewer rows than the window
    noisy = list(np.random.default_rng(0).normal(size=30))
    rising = [v + i for i, v in enumerate(noisy)]  # best at the end: exactly the final return
    assert numbers.peak_return(range(30), rising)[0] == numbers.final_return(range(30), rising)
    assert all(math.isnan(v) for v in numbers.peak_return([1, 2], [None, float("nan")]))


def test_exploration_std_is_the_mean_std_of_the_logged_log_stds():
    row = {"policy/log_std_0": math.log(0.1), "policy/log_std_1": math.log(0.3), "x": 5.0}
    assert numbers.exploration_std(row) == pytest.approx(0.2)
    assert math.isnan(numbers.exploration_std({"charts/SPS": 1.0}))


def test_smoothness_uses_medians_not_means():
    """One rough seed carries the mean; the median over seeds is the seeds' typical value."""
    cpg = [4.3e-4, 7.4e-4, 4.9e-3, 6.9e-3, 6.1e-4]  # the CPG-Actor at 20M steps, per seed
    assert st.mean_std(cpg)[0] == pytest.approx(2.72e-3, rel=0.01)
    assert st.bootstrap(cpg).estimate == pytest.approx(7.4e-4)


def alone(claim):
    """A claim's verdict with its own tests as the family."""
    return st.decide([claim])[0]


# Each verdict on synthetic per-seed results: (supporting results, contradicting results),
# each a function of the number of seeds n that returns the verdict.
_PASS_FAIL = {
    "reward ratio": (
        lambda n: paper.verdict_reward_ratio([600.0, 620.0, 580.0, 610.0, 590.0][:n],
                                         [100.0, 105.0, 98.0, 102.0, 95.0][:n]),
        lambda n: paper.verdict_reward_ratio([440.0, 420.0, 460.0, 450.0, 430.0][:n],
                                         [640.0, 650.0, 630.0, 660.0, 620.0][:n]),
    ),
    "open loop better": (
        lambda n: paper.verdict_better([600.0, 610.0, 620.0, 605.0][:n],
                                   {"cho2019-warm": [400.0, 410.0, 420.0, 415.0][:n]}),
        lambda n: paper.verdict_better([490.0, 500.0, 480.0, 510.0][:n],
                                   {"cho2019-warm": [640.0, 650.0, 630.0, 645.0][:n]}),
    ),
    "smooth": (
        lambda n: paper.verdict_smooth([1e-5, 2e-5, 3e-5, 1.5e-5, 2.5e-5][:n],
                                   [5e-3, 6e-3, 7e-3, 5.5e-3, 6.5e-3][:n]),
        # the 20M-step reproduction's per-seed values: the mean passed neither
        lambda n: paper.verdict_smooth([4.3e-4, 7.4e-4, 4.9e-3, 6.9e-3, 6.1e-4][:n],
                                   [3.31e-3, 4.09e-3, 4.86e-3, 7.90e-3, 6.28e-3][:n]),
    ),
    "near limits": (
        lambda n: paper.verdict_near_limits([14.0, 15.0, 16.0, 13.0, 14.5][:n],
                                        [0.99, 0.98, 0.97, 0.99, 0.99][:n]),
        lambda n: paper.verdict_near_limits([14.5, 20.0, 66.8, 75.6, 19.2][:n]),
    ),
    "hop doubles": (
        lambda n: paper.verdict_hop_doubles([0.42, 0.44, 0.40, 0.41][:n],
                                            [0.20, 0.21, 0.19, 0.2][:n], 1e6, 2e6),
        lambda n: paper.verdict_hop_doubles([0.27, 0.26, 0.28, 0.27][:n],
                                            [0.26, 0.27, 0.27, 0.25][:n], 1e6, 20e6),
    ),
    "best during training": (
        lambda n: paper.verdict_best_during_training([5.0, 6.0, 7.0, 6.5][:n],
                                                 {"mlp": [1.0, 2.0, 1.5, 1.2][:n]}),
        lambda n: paper.verdict_best_during_training(
            [5.0, 6.0, 7.0, 6.5][:n],
            {"mlp": [1.0, 2.0, 1.5, 1.2][:n], "cho": [8.0, 9.0, 8.5, 8.2][:n]},
        ),
    ),
    "cho flat": (
        lambda n: paper.verdict_cho_flat(
            {"theta_dot": [3.0, 3.2, 2.9, 3.1][:n], "r_ddot": [20.0, 22.0, 21.0, 19.0][:n]},
            {"cho2019-warm": {"theta_dot": [0.3, 0.31, 0.29, 0.3][:n],
                              "r_ddot": [1.0, 1.1, 0.9, 1.0][:n]}},
        ),
        lambda n: paper.verdict_cho_flat(
            {"theta_dot": [2.9, 3.0, 3.1, 2.8][:n], "r_ddot": [20.0, 22.0, 21.0, 19.0][:n]},
            {"cho2019-warm": {"theta_dot": [9.2, 9.0, 8.8, 9.1][:n],
                              "r_ddot": [1.0, 1.1, 0.9, 1.0][:n]}},
        ),
    ),
}  # fmt: skip


@pytest.mark.parametrize("claim", sorted(_PASS_FAIL))
def test_each_verdict_both_ways_and_not_tested_with_fewer_than_3_seeds(claim):
    supporting, contradicting = _PASS_FAIL[claim]
    for n in (3, 4):
        assert alone(supporting(n))[0] == st.SUPPORTED, (n, alone(supporting(n)))
        assert alone(contradicting(n))[0] == st.NOT_SUPPORTED, (n, alone(contradicting(n)))
    for n in (0, 1, 2):
        for verdict in (supporting, contradicting):
            result, detail = alone(verdict(n))
            assert result == st.NOT_TESTED, (n, detail)
            assert "[" not in detail  # no interval without enough seeds


def test_verdict_edge_cases():
    # any side short of seeds: not tested, with the counts
    verdict, detail = alone(paper.verdict_better([1.0, 2.0, 3.0], {"cho2019-warm": [1.0] * 3,
                                                               "cho2019": [1.0, 2.0]}))  # fmt: skip
    assert verdict == st.NOT_TESTED and "cho2019 2" in detail
    verdict, detail = alone(paper.verdict_smooth(None, [1.0, 2.0, 3.0]))
    assert verdict == st.NOT_TESTED and "cpg-actor not run" in detail
    assert alone(paper.verdict_better([1.0] * 3, {}))[0] == st.NOT_TESTED
    assert alone(paper.verdict_best_during_training([1.0] * 3, {}))[0] == st.NOT_TESTED
    assert alone(paper.verdict_cho_flat(None, {}))[0] == st.NOT_TESTED
    # NaN seeds (no data) do not count
    assert alone(paper.verdict_near_limits([14.0, 15.0, float("nan")]))[0] == st.NOT_TESTED
    # a ratio of returns needs a positive denominator
    negative = paper.verdict_reward_ratio([1.0, 2.0, 3.0], [-1.0, -2.0, -3.0])
    assert alone(negative)[0] == st.NOT_SUPPORTED
    # the reward ratio needs a significant difference as well as the estimate near 6
    wide = alone(paper.verdict_reward_ratio([10.0, 1200.0, 600.0], [100.0, 100.0, 100.0]))
    assert wide[0] == st.NOT_SUPPORTED
    # the hop height: too short a run, or not logged at 1M steps
    assert alone(paper.verdict_hop_doubles([0.4] * 3, [0.2] * 3, 1e6, 1.5e6))[0] == st.NOT_TESTED
    nan3 = [float("nan")] * 3
    assert alone(paper.verdict_hop_doubles([0.4] * 3, nan3, 1e6, 2e6))[0] == st.NOT_TESTED
    # ratios of medians: a flat (0) smaller side is an infinite ratio, a flat larger side none
    assert paper.ratio_of_medians([5.0, 6.0, 7.0], [0.0, 0.0, 0.0]).low == math.inf
    assert paper.ratio_of_medians([0.0, 0.0, 1.0], [1.0, 2.0, 3.0]) is None
    assert (
        alone(paper.verdict_smooth([0.0] * 3, [5e-3, 6e-3, 7e-3]))[0] == st.SUPPORTED
    )  # straight lines
    flat_mlp = paper.verdict_smooth([1e-5] * 3, [0.0] * 3)  # the MLP flat too
    assert alone(flat_mlp)[0] == st.NOT_SUPPORTED
    flat_cho = {"cho2019": {"theta_dot": [0.0] * 3, "r_ddot": [0.0] * 3}}
    moving = {"theta_dot": [3.0, 3.1, 2.9], "r_ddot": [20.0, 21.0, 22.0]}
    assert alone(paper.verdict_cho_flat(moving, flat_cho))[0] == st.SUPPORTED
    flat_cpg = paper.verdict_cho_flat(flat_cho["cho2019"], {"cho2019": moving})
    assert alone(flat_cpg)[0] == st.NOT_SUPPORTED
    # the velocity band is judged by a test: a mean inside it with seeds far outside fails
    assert alone(paper.verdict_near_limits([14.0, 15.0, 40.0, 3.0, 16.0]))[0] == st.NOT_SUPPORTED


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
    """cpg-actor-unbounded trains cpg-actor-paper with the paper's linear feedback; the
    reproduction's own --set still wins over the variant's settings."""
    assert parse_variants("cpg-actor-unbounded") == ["cpg-actor-unbounded"]
    settings = ReproduceSettings(
        variants=["cpg-actor-unbounded"], seeds=1, total_steps=4096,
        overrides=["agent_config.kappa_scale=2.0"],
    )  # fmt: skip
    config = resolve_config(settings, "cpg-actor-unbounded")
    assert config.agent == "cpg-actor-paper" and config.agent_config.feedback_tanh is False
    assert (config.agent_config.xi_scale, config.agent_config.kappa_scale) == (1.0, 2.0)
    (task,) = build_tasks(settings, tmp_path, workers=1)
    args = list(task.train_args)
    assert args[args.index("--agent") + 1] == "cpg-actor-paper"
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
    (out / "keep").write_text("x")  # not written by reproduce: --overwrite deletes nothing
    with pytest.raises(FileExistsError, match="did not write \\(keep\\)"):
        prepare_out_dir(out, other, overwrite=True)
    assert (out / "keep").read_text() == "x" and (out / "reproduce.yaml").is_file()
    (out / "keep").unlink()
    assert prepare_out_dir(out, other, overwrite=True) == "overwrite"
    assert not (out / "reproduce.yaml").exists()
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "data.txt").write_text("x")
    with pytest.raises(FileExistsError, match="not written by"):
        prepare_out_dir(foreign, settings, overwrite=True)


def test_bound_share_counts_feedback_at_its_bound_and_variability_flat_signals():
    from cpg_actor_studies.reproduction.numbers import bound_share, variability

    t = np.linspace(0, 5, 500)
    bang_bang = 4.0 * np.tanh(50 * np.sin(2 * np.pi * 2 * t))  # at +-4 nearly always
    smooth = 4.0 * np.tanh(0.5 * np.sin(2 * np.pi * 2 * t))
    assert bound_share(bang_bang, 4.0) > 0.9
    assert bound_share(smooth, 4.0) == 0.0
    flat = np.full((500, 3, 2), 4 * np.pi)
    moving = flat + 2.0 * np.sin(2 * np.pi * t)[:, None, None]
    assert variability(flat) == pytest.approx(0.0, abs=1e-9)
    assert variability(moving) == pytest.approx(2.0 / np.sqrt(2), rel=0.02)
