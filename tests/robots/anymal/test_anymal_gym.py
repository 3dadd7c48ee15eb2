"""AnymalEnv, the quadruped as a single-robot Gymnasium env (``cpg_actor/AnymalB-v0`` with
``gymnasium.make``): Gymnasium's and Stable-Baselines3's checkers, SB3's PPO, the vector env's
trajectories, seeding, bad input and the docs' example."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from cpg_actor.robots.anymal import description as robot
from cpg_actor.robots.anymal.env import AnymalEnv
from cpg_actor.robots.anymal.plugin import ENV_ID as ANYMAL_ENV_ID
from cpg_actor.robots.anymal.plugin import MJX_ENV_ID as ANYMAL_MJX_ENV_ID
from cpg_actor.robots.anymal.plugin import ROBOT as ANYMAL
from cpg_actor.robots.anymal.vector import AnymalVectorEnv
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig

NOMINAL = np.array(robot.NOMINAL_POSE)
DOC = Path(__file__).resolve().parents[3] / "docs" / "quadruped.md"
# Gymnasium's remarks on the spaces, which are the task's: the actions are radians (unless
# normalized_actions), the observations are not bounded
SPACE_REMARKS = ("symmetric and normalized", "observation space minimum value is -infinity",
                 "observation space maximum value is infinity")  # fmt: skip


def sb3():
    return pytest.importorskip(
        "stable_baselines3", reason="stable-baselines3 is not installed (pip install -e .[test])"
    )


def remarks(caught) -> list[str]:
    """The warnings that are not about the spaces."""
    messages = [str(w.message) for w in caught]
    return [m for m in messages if not any(remark in m for remark in SPACE_REMARKS)]


def actions(steps: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return NOMINAL + 0.2 * rng.standard_normal((steps, 12))


def test_registered_for_make_with_the_vector_envs_episode_length():
    assert ANYMAL.episode_steps == QuadrupedConfig().episode_steps == 1000
    assert gym.spec(ANYMAL_ENV_ID).max_episode_steps == ANYMAL.episode_steps
    env = gym.make(ANYMAL_ENV_ID)
    assert isinstance(env.unwrapped, AnymalEnv)
    assert env.spec.max_episode_steps == env.unwrapped.config.episode_steps
    assert env.metadata["render_fps"] == round(1 / env.unwrapped.config.control_dt)
    assert env.observation_space.shape == (45,) and env.action_space.shape == (12,)
    assert env.unwrapped.robot.name == "anymal-b"
    env.close()
    with pytest.raises(ValueError, match="make_vec"):
        gym.make(ANYMAL_MJX_ENV_ID)  # no single-robot MJX env


def test_batched_ids_still_make_the_vector_env():
    vec = gym.make_vec(ANYMAL_ENV_ID, num_envs=2)
    assert isinstance(vec, AnymalVectorEnv) and vec.reset(seed=0)[0].shape == (2, 45)
    vec.close()
    # the spec's episode length reaches the vector env: a config with another one needs both
    with pytest.raises(ValueError, match="max_episode_steps=1000 differs"):
        gym.make_vec(ANYMAL_ENV_ID, num_envs=2, config={"episode_seconds": 1.0})
    vec = gym.make_vec(ANYMAL_ENV_ID, 2, config={"episode_seconds": 1.0}, max_episode_steps=50)
    assert vec.config.episode_steps == 50
    vec.close()
    # Gymnasium's own vectorisation of the single env works too
    sync = gym.make_vec(ANYMAL_ENV_ID, num_envs=2, vectorization_mode="sync")
    obs, _ = sync.reset(seed=0)
    assert obs.shape == (2, 45)
    assert np.isfinite(sync.step(np.tile(NOMINAL, (2, 1)).astype(np.float32))[1]).all()
    sync.close()


@pytest.mark.parametrize("normalized", [False, True])
def test_gymnasium_checkers_pass(normalized):
    env = gym.make(ANYMAL_ENV_ID, normalized_actions=normalized)  # the passive checker too
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped, skip_render_check=True)
        env.reset(seed=0)
        for _ in range(3):
            env.step(env.action_space.sample())
    assert not remarks(caught)
    messages = [str(w.message) for w in caught]
    assert any("symmetric and normalized" in m for m in messages) != normalized
    env.close()


def test_stable_baselines3_checker_and_ppo():
    sb3()
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make(ANYMAL_ENV_ID)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sb3_check_env(env)
    assert not remarks(caught)
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=64, n_epochs=1, seed=0, device="cpu")
    model.learn(256)
    assert model.num_timesteps == 256
    obs, _ = env.reset(seed=1)
    action, _ = model.predict(obs, deterministic=True)
    assert env.action_space.contains(action)
    env.close()


def test_same_trajectory_as_the_vector_env_episodes_included():
    """Same seed, same actions: the single env's steps are env 0's of the vector env, across
    episode ends (15-step episodes; reset() after each, as an agent does)."""
    config = {"episode_seconds": 0.3}
    single, vec = AnymalEnv(config), AnymalVectorEnv(1, config)
    obs, info = single.reset(seed=11)
    batch, batch_info = vec.reset(seed=11)
    np.testing.assert_allclose(obs, batch[0], rtol=1e-6)
    np.testing.assert_allclose(info["command"], batch_info["command"][0], rtol=1e-6)
    ends = 0
    for action in actions(40):
        obs, reward, terminated, truncated, info = single.step(action)
        batch, rewards, terms, truncs, batch_info = vec.step(action[None])
        assert (terminated, truncated) == (terms[0], truncs[0])
        assert reward == pytest.approx(rewards[0], rel=1e-6)
        np.testing.assert_allclose(info["command"], batch_info["command"][0], rtol=1e-6)
        for name, value in info["reward_terms"].items():
            assert value == pytest.approx(batch_info["reward_terms"][name][0], rel=1e-6)
        if terminated or truncated:
            ends += 1
            np.testing.assert_allclose(obs, batch_info["final_obs"][0], rtol=1e-6)
            assert set(info["episode_metrics"]) == set(batch_info["episode_metrics"])
            assert info["episode_metrics"]["episode_seconds"] == pytest.approx(0.3, rel=1e-9)
            obs, info = single.reset()  # the episode the vector env's autoreset started
        else:
            assert "episode_metrics" not in info
        np.testing.assert_allclose(obs, batch[0], rtol=1e-6)
    assert ends == 2
    single.close()
    vec.close()


def test_seeding_resets_and_np_random():
    env = AnymalEnv()
    first, info = env.reset(seed=3)
    assert first.dtype == np.float32 and env.observation_space.contains(first)
    assert 0.0 <= info["command"][0] <= 1.0
    assert np.array_equal(env.reset(seed=3)[0], first)  # same seed, same start
    assert not np.array_equal(env.reset(seed=4)[0], first)
    env.reset(seed=3)
    assert not np.array_equal(env.reset()[0], first)  # the stream goes on
    # the draws come from np_random: a generator handed over is used
    env.np_random = np.random.default_rng(3)
    other = AnymalEnv()
    other.np_random = np.random.default_rng(3)
    assert np.array_equal(env.reset()[0], other.reset()[0])
    env.close()
    other.close()


def test_overrides_render_mode_and_bad_input():
    env = gym.make(ANYMAL_ENV_ID, normalized_actions=True, reward_scales={"feet_slip": -0.1})
    config = env.unwrapped.config
    assert config.normalized_actions and config.reward_scales["feet_slip"] == -0.1
    assert config.reward_scales["tracking_lin_vel"] == 1.0  # the others kept
    assert env.action_space == gym.spaces.Box(-1.0, 1.0, (12,), np.float32)
    env.close()
    env = AnymalEnv(QuadrupedConfig(kp=100.0), episode_seconds=0.1)
    assert (env.config.kp, env.config.episode_steps) == (100.0, 5)
    with pytest.raises(gym.error.ResetNeeded):
        env.step(NOMINAL)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(12,\)"):
        env.step(np.zeros(2))
    with pytest.raises(ValueError, match="12 numbers"):
        env.step("forward")
    with pytest.raises(ValueError, match="finite"):
        env.step(np.full(12, np.nan))
    for _ in range(5):
        *_, truncated, _ = env.step(NOMINAL)
    assert truncated
    with pytest.raises(gym.error.ResetNeeded):  # the episode ended
        env.step(NOMINAL)
    env.close()
    env.close()  # twice is fine
    with pytest.raises(gym.error.ClosedEnvironmentError):
        env.reset(seed=0)
    with pytest.raises(ValueError, match="unknown QuadrupedConfig fields"):
        AnymalEnv(gain=3.0)
    with pytest.raises(ValueError, match="render_mode must be None or one of"):
        AnymalEnv(render_mode="human")
    with pytest.raises(ValueError, match="config must be a QuadrupedConfig or a dict"):
        AnymalEnv(config=3)


def test_renders_rgb_frames():
    from robots.hopper.test_render_video import mujoco_gl_error

    reason = mujoco_gl_error()
    if reason is not None:
        pytest.skip(f"no MuJoCo GL context: {reason}")
    env = gym.make(ANYMAL_ENV_ID, render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (480, 640, 3) and frame.dtype == np.uint8
    assert frame.std() > 10  # a picture, not a blank
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    assert not remarks(caught)
    env.close()


def test_docs_example_runs(capsys):
    """docs/quadruped.md's Gymnasium / Stable-Baselines3 example, as written."""
    sb3()
    text = DOC.read_text(encoding="utf-8")
    section = text.split("## Using it from Gymnasium / Stable-Baselines3", 1)[1].split("\n## ")[0]
    blocks = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    assert len(blocks) == 1, "the section should hold exactly one Python example"
    exec(compile(blocks[0], str(DOC), "exec"), {"__name__": "docs_example"})
    assert "mean reward" in capsys.readouterr().out
