"""Checkpoints hold the episodes in progress: checkpointing changes nothing that is trained,
cuts no episode, and a run resumed from any checkpoint equals the uninterrupted run (MuJoCo,
bit for bit)."""

import numpy as np
import pytest
import torch

from cpg_actor.config import TrainConfig
from cpg_actor.robots.hopper.vector import HopperVectorEnv
from cpg_actor.training.runner import Runner
from extras import MJX  # tests/extras.py (pytest puts tests/ on sys.path)
from tiny import tiny_config

EPISODE = 12  # control steps: several episodes end inside the 6 iterations of 8 steps


def config(agent: str) -> TrainConfig:
    cfg = tiny_config(agent, iterations=6, checkpoint_interval=1)
    cfg.env.episode_steps = EPISODE
    return cfg


def params(runner: Runner) -> dict[str, torch.Tensor]:
    return {k: v.clone() for k, v in runner.agent.state_dict().items()}


@pytest.mark.parametrize("agent", ["cpg-actor", "cho2019"])
def test_checkpoint_every_iteration_changes_nothing_and_cuts_no_episode(tmp_path, agent):
    saved = Runner(config(agent), run_dir=tmp_path / "saved", tensorboard=False)
    saved.learn()
    plain = Runner(config(agent), run_dir=None, tensorboard=False)
    plain.learn()
    try:
        for key, value in params(saved).items():
            assert torch.equal(value, params(plain)[key]), key
        recent = saved.rollout.episodes.recent
        assert list(recent["return"]) == list(plain.rollout.episodes.recent["return"])
        # every episode ran to its time limit: 6 iterations x 8 steps = 4 episodes of 12
        assert list(recent["length"]) == [EPISODE] * 8
        assert len(list((tmp_path / "saved" / "checkpoints").glob("iter_*.pt"))) == 7
    finally:
        saved.close()
        plain.close()


def same_state(a, b) -> bool:
    """Env states (nested dicts / lists of tensors and plain values) equal, bit for bit."""
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same_state(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(same_state(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, torch.Tensor):
        return torch.equal(a, b)
    return a == b


@pytest.mark.parametrize(
    ("agent", "sim"),
    [
        ("cpg-actor", "mujoco"),
        ("mlp", "mujoco"),
        pytest.param(
            "cpg-actor", "mjx",
            marks=[MJX, pytest.mark.slow],
        ),
    ],
)  # fmt: skip
def test_resume_from_a_middle_checkpoint_equals_the_uninterrupted_run(tmp_path, agent, sim):
    cfg = config(agent)
    cfg.env.sim = sim
    straight = Runner(cfg, run_dir=tmp_path / "run", tensorboard=False)
    straight.learn()
    resumed = Runner(cfg, run_dir=tmp_path / "copy", tensorboard=False)
    resumed.load_checkpoint(tmp_path / "run" / "checkpoints" / "iter_000003.pt")
    assert resumed.iteration == 3
    resumed.learn()
    try:
        for key, value in params(straight).items():
            assert torch.equal(value, params(resumed)[key]), key
        assert torch.equal(straight.rollout.obs, resumed.rollout.obs)
        assert torch.equal(straight.policy.state, resumed.policy.state)
        recent = straight.rollout.episodes.recent
        assert list(recent["return"]) == list(resumed.rollout.episodes.recent["return"])
        # episodes ended in both halves (6 iterations x 8 steps cross the 12-step episodes)
        assert list(recent["length"]) == [EPISODE] * 8
        assert same_state(straight.env.get_state(), resumed.env.get_state())
    finally:
        straight.close()
        resumed.close()


@pytest.mark.parametrize("sim", ["mujoco", "pybullet"])
def test_env_state_round_trip(sim):
    """MuJoCo continues bit for bit from a saved state; PyBullet restores the joint states."""
    rng = np.random.default_rng(0)
    actions = [np.array([0.4, -0.8]) + 0.3 * rng.standard_normal((3, 2)) for _ in range(30)]
    env = HopperVectorEnv(3, sim=sim, episode_steps=20)
    env.reset(seed=5)
    for action in actions[:10]:
        env.step(action)
    state = env.get_state()
    expected = [env.step(action) for action in actions[10:]]
    other = HopperVectorEnv(3, sim=sim, episode_steps=20)
    with pytest.raises(RuntimeError, match="reset"):
        other.get_state()
    other.set_state(state)
    try:
        if sim == "mujoco":
            for action, (obs, reward, _, truncated, _) in zip(actions[10:], expected, strict=True):
                step = other.step(action)
                assert np.array_equal(step[0], obs) and np.array_equal(step[1], reward)
                assert np.array_equal(step[3], truncated)
        else:
            restored = other.get_state()["simulation"]
            assert torch.equal(restored["backend"], state["simulation"]["backend"])
            assert torch.equal(restored["elapsed_steps"], state["simulation"]["elapsed_steps"])
        with pytest.raises(ValueError, match="has 3 envs, this env 2"):
            HopperVectorEnv(2, sim=sim).set_state(state)
    finally:
        env.close()
        other.close()
