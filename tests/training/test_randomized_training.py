"""Randomised training (``env.randomize``): a run is reproducible from its seed, and one
resumed from a middle checkpoint equals the uninterrupted run, bit for bit (the episodes'
draws and the robots' physics are in the checkpoints)."""

import pytest
import torch

from cpg_actor.config import apply_dict
from cpg_actor.training.runner import Runner
from tiny import tiny_config  # tests/tiny.py (pytest puts tests/ on sys.path)

RANDOMIZE = {"payload": [0.0, 1.0], "friction": [0.4, 1.2], "latency": [0.0, 2.0],
             "obs_noise": [0.0, 1.0], "motor_strength": [0.8, 1.2]}  # fmt: skip


def config(robot: str, seed: int = 0):
    cfg = tiny_config("mlp", iterations=6, checkpoint_interval=1, seed=seed)
    env = {"episode_steps": 12} if robot == "hopper" else {"episode_seconds": 0.24}
    apply_dict(cfg, {"robot": robot, "env": {**env, "randomize": RANDOMIZE}}, "")
    return cfg


def params(runner: Runner) -> dict[str, torch.Tensor]:
    return {k: v.clone() for k, v in runner.agent.state_dict().items()}


@pytest.mark.parametrize("robot", ["hopper", "anymal"])
def test_randomised_training_is_reproducible_and_resumes_exactly(tmp_path, robot):
    straight = Runner(config(robot), run_dir=tmp_path / "run", tensorboard=False)
    straight.learn()
    twin = Runner(config(robot), run_dir=None, tensorboard=False)
    twin.learn()
    other = Runner(config(robot, seed=1), run_dir=None, tensorboard=False)
    other.learn()
    resumed = Runner(config(robot), run_dir=tmp_path / "copy", tensorboard=False)
    resumed.load_checkpoint(tmp_path / "run" / "checkpoints" / "iter_000003.pt")
    resumed.learn()
    try:
        for key, value in params(straight).items():
            assert torch.equal(value, params(twin)[key]), key
            assert torch.equal(value, params(resumed)[key]), key
        assert any(not torch.equal(v, params(other)[k]) for k, v in params(straight).items())
        recent = straight.rollout.episodes.recent
        assert list(recent["return"]) == list(resumed.rollout.episodes.recent["return"])
        assert len(recent["return"]) >= 4  # episodes ended (and were drawn anew) in both halves
        assert straight.env.get_state().keys() == resumed.env.get_state().keys()
    finally:
        for runner in (straight, twin, other, resumed):
            runner.close()
