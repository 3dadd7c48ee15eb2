"""The evaluation during training gives the physical metrics (the hop apex) when asked, and
the same return, lengths and env metrics either way (the time-to-quality benchmark asks)."""

import pytest

from cpg_actor.config import compose_config
from cpg_actor.metrics.physical import episode_metrics
from cpg_actor.training.runner import Runner


def test_the_training_evaluation_adds_the_hop_apex_only_when_asked():
    config = compose_config(None, None, {"agent": "cpg-actor", "total_steps": 64,
                                         "num_envs": 2, "eval_episodes": 2})  # fmt: skip
    config.ppo.compile = False
    config.env.episode_steps = 300  # flights after the apex's start-up second
    runner = Runner(config, run_dir=None, tensorboard=False)
    try:
        plain = runner.evaluation()
        runner.evaluation.traced_metrics = episode_metrics
        physical = runner.evaluation()
    finally:
        runner.close()
    assert "eval/hop_apex" not in plain
    assert physical["eval/hop_apex"] > 0  # the searched start gait hops
    # the apex is no higher than the episode's highest hip height
    assert physical["eval/hop_apex"] <= physical["eval/hop_height"]
    for key in ("eval/return", "eval/length", "eval/hop_height"):
        assert physical[key] == pytest.approx(plain[key], rel=1e-9)
