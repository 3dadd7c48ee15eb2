"""HopperVectorEnv: same semantics as N single HopperEnvs, SAME_STEP autoreset, the contract."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, VectorEnv

from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.env import HopperEnv
from cpg_actor.robots.hopper.plugin import ENV_ID
from cpg_actor.robots.hopper.vector import HopperVectorEnv, make_vector_env

from .helpers import NOMINAL, SIMS


def random_actions(steps: int, num_envs: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform([-0.5, -1.7], [1.3, 0.1], size=(steps, num_envs, 2)).astype(np.float32)


def run_vector(env: HopperVectorEnv, actions: np.ndarray, seed: int):
    obs, _ = env.reset(seed=seed)
    log = {"obs": [obs], "reward": [], "terminated": [], "truncated": [], "final_obs": [],
           "r1": []}  # fmt: skip
    for action in actions:
        obs, reward, terminated, truncated, info = env.step(action)
        log["obs"].append(obs)
        log["reward"].append(reward)
        log["terminated"].append(terminated)
        log["truncated"].append(truncated)
        log["final_obs"].append(info["final_obs"])
        log["r1"].append(info["reward_terms"]["r1"])
    return {k: np.array(v) for k, v in log.items()}


@pytest.mark.parametrize("sim", SIMS)
def test_vector_env_equals_single_envs_stepped_one_by_one(sim):
    """Same seeds and actions, through two autoresets: identical to the last bit."""
    config = HopperConfig(sim=sim, episode_steps=15)
    num_envs, steps, seed = 3, 40, 11
    actions = random_actions(steps, num_envs)
    vector = HopperVectorEnv(num_envs, config, num_threads=2)
    log = run_vector(vector, actions, seed)
    vector.close()
    for i in range(num_envs):
        single = HopperEnv(config)
        obs, _ = single.reset(seed=seed + i)
        np.testing.assert_array_equal(obs, log["obs"][0, i])
        for t in range(steps):
            obs, reward, terminated, truncated, info = single.step(actions[t, i])
            assert reward == log["reward"][t, i]
            assert info["reward_terms"]["r1"] == log["r1"][t, i]
            assert (terminated, truncated) == (log["terminated"][t, i], log["truncated"][t, i])
            if terminated or truncated:
                np.testing.assert_array_equal(obs, log["final_obs"][t, i])
                obs, _ = single.reset()
            np.testing.assert_array_equal(obs, log["obs"][t + 1, i])
        single.close()
    assert log["truncated"][14].all() and log["truncated"][29].all()
    assert not log["terminated"].any()


def test_pybullet_robots_in_several_worlds_equal_single_envs():
    """18 robots: PyBullet worlds of 16 and 2; robots 0, 15, 16, 17 against single envs."""
    config = HopperConfig(sim="pybullet", episode_steps=8)
    actions = random_actions(12, 18, seed=3)
    vector = HopperVectorEnv(18, config)
    log = run_vector(vector, actions, seed=2)
    vector.close()
    for i in (0, 15, 16, 17):
        single = HopperEnv(config)
        obs, _ = single.reset(seed=2 + i)
        for t in range(12):
            obs, _, terminated, truncated, _ = single.step(actions[t, i])
            if terminated or truncated:
                obs, _ = single.reset()
            np.testing.assert_array_equal(obs, log["obs"][t + 1, i])
        single.close()


def test_thread_count_does_not_change_results():
    actions = random_actions(20, 40)
    logs = []
    for threads in (1, 2, 3):
        env = HopperVectorEnv(40, HopperConfig(episode_steps=12), num_threads=threads)
        assert env.num_threads == threads
        logs.append(run_vector(env, actions, seed=5))
        env.close()
    for log in logs[1:]:
        for key in logs[0]:
            np.testing.assert_array_equal(log[key], logs[0][key], err_msg=key)


@pytest.mark.parametrize("sim", SIMS)
def test_autoreset_same_step(sim):
    env = HopperVectorEnv(4, HopperConfig(sim=sim, episode_steps=3))
    assert env.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    obs0, _ = env.reset(seed=0)
    for _ in range(3):
        obs, reward, terminated, truncated, info = env.step(np.tile(NOMINAL, (4, 1)) + 0.2)
    assert truncated.all() and not terminated.any()
    assert info["_final_obs"].all()
    # the returned obs starts the next episode: tracking the nominal pose again, at rest
    np.testing.assert_allclose(obs[:, 4:6], np.tile(NOMINAL, (4, 1)), atol=1e-7)
    np.testing.assert_array_equal(obs[:, [2, 3, 7]], 0.0)
    # the final obs is where the finished episode ended: tracking nominal + 0.2
    np.testing.assert_allclose(info["final_obs"][:, 4:6], np.tile(NOMINAL + 0.2, (4, 1)), atol=1e-6)
    # new episode, new noise (each env's generator continues)
    assert not np.array_equal(obs[:, 0:2], obs0[:, 0:2])
    obs, *_ = env.step(np.tile(NOMINAL, (4, 1)))  # and stepping goes on
    assert np.isfinite(obs).all()
    env.close()


def test_blow_up_in_one_env_resets_only_that_env():
    env = HopperVectorEnv(3, HopperConfig())
    env.reset(seed=0)
    env.sim.backend.qpos[1, 0] = np.nan
    obs, reward, terminated, truncated, info = env.step(np.tile(NOMINAL, (3, 1)))
    assert terminated.tolist() == [False, True, False] and not truncated.any()
    assert reward[1] == 0.0 and np.isfinite(obs).all() and np.isfinite(info["final_obs"]).all()
    np.testing.assert_array_equal(obs[1, [2, 3, 7]], 0.0)  # env 1 restarted at rest
    env.close()


def test_contract_attributes_and_info():
    env = make_vector_env(5, HopperConfig(sim="mujoco"))
    assert isinstance(env, VectorEnv) and env.num_envs == 5
    assert env.single_observation_space.shape == (8,)
    assert env.single_action_space.shape == (2,)
    assert env.observation_space.shape == (5, 8) and env.action_space.shape == (5, 2)
    obs, info = env.reset(seed=1)
    assert obs.shape == (5, 8) and obs.dtype == np.float32
    assert env.observation_space.contains(obs)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert obs.dtype == np.float32 and reward.shape == (5,)
    assert terminated.dtype == bool and truncated.dtype == bool
    assert terminated.shape == truncated.shape == (5,)
    assert set(info["reward_terms"]) == {"r1", "r2", "r3", "r4", "r5"}
    for key in ("hip_height", "foot_height"):
        assert info[key].shape == (5,)
    assert info["joint_torque"].shape == (5, 2)
    assert info["final_obs"].shape == (5, 8)
    np.testing.assert_allclose(reward, sum(info["reward_terms"].values()))
    env.close()
    assert env.closed


def test_seeding():
    env = HopperVectorEnv(3, HopperConfig())
    a, _ = env.reset(seed=4)
    b, _ = env.reset(seed=[4, 5, 6])
    np.testing.assert_array_equal(a, b)
    c, _ = env.reset(seed=4)
    np.testing.assert_array_equal(a, c)
    d, _ = env.reset()  # continues the generators
    assert not np.array_equal(a, d)
    single = HopperEnv()
    np.testing.assert_array_equal(single.reset(seed=6)[0], a[2])
    with pytest.raises(ValueError, match="seed"):
        env.reset(seed=[1, 2])
    unseeded = HopperVectorEnv(2, HopperConfig())
    assert np.isfinite(unseeded.reset()[0]).all()
    for e in (env, single, unseeded):
        e.close()


def test_bad_input():
    env = HopperVectorEnv(2, HopperConfig())
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.tile(NOMINAL, (2, 1)))
    env.reset(seed=0)
    before = env.sim.backend.qpos.copy()
    for bad in (np.zeros((2, 3)), np.zeros((3, 2)), np.zeros(2), [[np.nan, 0.0], [0.0, 0.0]],
                [[0.0, 0.0], [np.inf, 0.0]]):  # fmt: skip
        with pytest.raises(ValueError):
            env.step(bad)
    np.testing.assert_array_equal(env.sim.backend.qpos, before)
    env.close()
    for num_envs in (0, -1, 2.5, True):
        with pytest.raises(ValueError, match="num_envs"):
            HopperVectorEnv(num_envs)
    with pytest.raises(ValueError, match="num_threads"):
        HopperVectorEnv(2, num_threads=0)
    with pytest.raises(ValueError, match="c3 must be <= 0"):
        HopperVectorEnv(2, c3=1.0)


def test_make_vec_uses_the_vector_env():
    env = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="vector_entry_point", sim="pybullet")
    assert isinstance(env, HopperVectorEnv) and env.config.sim == "pybullet"
    env.close()


def test_the_env_reports_each_finished_episode_hop_height():
    """hop_height = the episode's highest hip above the hip height it started at, reported at
    the step the episode ends (NaN for the other envs)."""
    env = HopperVectorEnv(3, episode_steps=15)
    obs, _ = env.reset(seed=4)
    standing, highest = obs[:, 6].astype(np.float64), np.full(3, -np.inf)
    rng = np.random.default_rng(1)
    reported = 0
    try:
        for _ in range(40):
            action = np.array([0.4, -0.8]) + 0.4 * rng.standard_normal((3, 2))
            obs, _, terminated, truncated, info = env.step(action)
            done = terminated | truncated
            highest = np.maximum(highest, info["hip_height"])
            hop = info["episode_metrics"]["hop_height"]
            assert np.isnan(hop[~done]).all()
            expected = np.maximum(0.0, highest - standing)
            np.testing.assert_allclose(hop[done], expected[done], rtol=0, atol=1e-6)
            reported += int(done.sum())
            standing[done], highest[done] = obs[done, 6], -np.inf
    finally:
        env.close()
    assert reported == 6  # two episodes of 15 steps per env in 40 steps
