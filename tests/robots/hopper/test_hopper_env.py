"""HopperEnv: Gymnasium compliance, the interface contract, determinism, bad input, episodes."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from gymnasium.utils.env_checker import check_env

from cpg_actor.robots.hopper import kinematics
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.env import HopperEnv
from cpg_actor.robots.hopper.plugin import ENV_ID, PYBULLET_ENV_ID
from cpg_actor.robots.hopper.task import OBS_NAMES

from .helpers import NOMINAL, SIMS

INFO_KEYS = {
    "reward_terms", "hip_height", "foot_height", "joint_torque", "desired_position",
    "measured_position", "measured_velocity", "foot_position",
}  # fmt: skip


@pytest.fixture(params=SIMS)
def env(request):
    env = HopperEnv(sim=request.param)
    yield env
    env.close()


def random_actions(steps: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform([-0.5, -1.7], [1.3, 0.1], size=(steps, 2)).astype(np.float32)


@pytest.mark.parametrize("env_id", [ENV_ID, PYBULLET_ENV_ID])
def test_check_env_passes(env_id):
    env = gym.make(env_id)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped, skip_render_check=True)
    messages = [str(w.message) for w in caught]
    # the only remark: the action space is in radians, not [-1, 1] (the contract wants radians)
    assert all("symmetric and normalized" in m for m in messages), messages
    env.close()


def test_registered_ids_and_kwargs():
    for env_id, sim in ((ENV_ID, "mujoco"), (PYBULLET_ENV_ID, "pybullet")):
        env = gym.make(env_id)
        assert env.unwrapped.config.sim == sim
        env.close()
    env = gym.make(ENV_ID, sim="pybullet", kp=100.0)
    assert env.unwrapped.config.sim == "pybullet" and env.unwrapped.config.kp == 100.0
    env.close()
    env = HopperEnv(config=HopperConfig(kd=3.0), sim="pybullet")
    assert (env.config.kd, env.config.sim) == (3.0, "pybullet")
    env.close()
    with pytest.raises(ValueError, match="unknown HopperConfig key"):
        HopperEnv(gain=3.0)


def test_spaces(env):
    assert env.action_space.shape == (2,) and env.action_space.dtype == np.float32
    np.testing.assert_allclose(env.action_space.low, [-0.5, -1.7])
    np.testing.assert_allclose(env.action_space.high, [1.3, 0.1])
    assert env.observation_space.shape == (8,) and env.observation_space.dtype == np.float32
    assert OBS_NAMES == (
        "p_m_HFE", "p_m_KFE", "v_m_HFE", "v_m_KFE", "p_d_HFE", "p_d_KFE", "hip_height",
        "hip_velocity",
    )  # fmt: skip


def test_reset_puts_the_robot_on_the_ground_near_the_nominal_pose(env):
    obs, info = env.reset(seed=3)
    assert obs.dtype == np.float32 and obs.shape == (8,)
    np.testing.assert_allclose(obs[4:6], NOMINAL, atol=1e-7)  # p_d = nominal after reset
    assert np.abs(obs[0:2] - NOMINAL).max() <= env.config.reset_noise
    assert np.abs(obs[0:2] - NOMINAL).max() > 0  # noise was added
    np.testing.assert_array_equal(obs[[2, 3, 7]], 0.0)
    assert obs[6] == pytest.approx(kinematics.standing_hip_height(obs[0:2]), abs=1e-6)
    assert info["foot_height"] == pytest.approx(0.0, abs=1e-6)


def test_step_returns_the_contract(env):
    obs, _ = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(np.array([0.6, -1.0], dtype=np.float32))
    assert obs.dtype == np.float32 and obs.shape == (8,)
    assert isinstance(reward, float) and isinstance(terminated, bool)
    assert isinstance(truncated, bool) and not terminated and not truncated
    assert set(info) == INFO_KEYS
    assert set(info["reward_terms"]) == {"r1", "r2", "r3", "r4", "r5"}
    assert reward == pytest.approx(sum(info["reward_terms"].values()))
    np.testing.assert_allclose(obs[4:6], [0.6, -1.0], atol=1e-6)  # p_d is the last action
    np.testing.assert_allclose(info["desired_position"], [0.6, -1.0], atol=1e-6)
    np.testing.assert_allclose(info["measured_position"], obs[0:2], atol=1e-6)
    assert info["hip_height"] == pytest.approx(obs[6], abs=1e-6)
    assert info["joint_torque"].shape == (2,)
    assert np.abs(info["joint_torque"]).max() <= 40.0


def test_same_seed_same_trajectory_other_seed_differs(env):
    actions = random_actions(40)

    def rollout(seed):
        obs, _ = env.reset(seed=seed)
        log = [obs]
        for action in actions:
            obs, reward, *_ = env.step(action)
            log.append(np.append(obs, reward))
        return log[0], np.array(log[1:])

    first0, run0 = rollout(7)
    first1, run1 = rollout(7)
    np.testing.assert_array_equal(first0, first1)
    np.testing.assert_array_equal(run0, run1)
    first2, _ = rollout(8)
    assert not np.array_equal(first0, first2)


@pytest.mark.parametrize(
    "action",
    [
        np.zeros(3), np.zeros((1, 2)), np.array(0.4), [0.4], [np.nan, -0.8], [0.4, np.inf],
        [-np.inf, -0.8], "up", [None, 1.0],
    ],
)  # fmt: skip
def test_bad_actions_raise_before_stepping(action):
    env = HopperEnv()
    env.reset(seed=0)
    before = env.sim.backend.qpos.copy()
    with pytest.raises(ValueError):
        env.step(action)
    np.testing.assert_array_equal(env.sim.backend.qpos, before)  # nothing was stepped
    env.close()


def test_out_of_range_actions_are_clipped(env):
    env.reset(seed=0)
    obs, *_, info = env.step(np.array([5.0, -5.0]))
    np.testing.assert_allclose(info["desired_position"], [1.3, -1.7], atol=1e-6)
    np.testing.assert_allclose(obs[4:6], [1.3, -1.7], atol=1e-6)


def test_time_limit_truncates(env):
    short = HopperEnv(sim=env.config.sim, episode_steps=5)
    short.reset(seed=0)
    flags = [short.step(NOMINAL)[2:4] for _ in range(5)]
    assert flags[:4] == [(False, False)] * 4 and flags[4] == (False, True)
    short.close()


def test_step_before_reset_is_an_error():
    env = HopperEnv()
    with pytest.raises(gym.error.ResetNeeded):
        env.step(NOMINAL)
    env.close()


def test_blow_up_terminates_and_reset_recovers(env):
    """A NaN in the state is caught (MuJoCo: by its reset-on-instability, PyBullet: non-finite),
    the observation stays finite, and the next episode is as good as new."""
    env.reset(seed=0)
    fresh = [env.step(NOMINAL)[0] for _ in range(3)]
    backend = env.sim.backend
    if env.config.sim == "mujoco":
        backend.qpos[0, 0] = np.nan
    else:
        client, body = backend.handle(0)
        client.resetJointState(body, 0, float("nan"), 0.0)
    obs, reward, terminated, truncated, info = env.step(NOMINAL)
    assert terminated and not truncated and reward == 0.0
    assert np.isfinite(obs).all() and env.observation_space.contains(obs)
    for key in ("hip_height", "foot_height", "joint_torque", "measured_position"):
        assert np.isfinite(info[key]).all(), key
    assert all(value == 0.0 for value in info["reward_terms"].values())
    with pytest.raises(gym.error.ResetNeeded):
        env.step(NOMINAL)
    env.reset(seed=0)
    again = [env.step(NOMINAL)[0] for _ in range(3)]
    np.testing.assert_array_equal(np.array(fresh), np.array(again))


def test_absurd_velocity_terminates(env):
    """Thresholds are config values: a 1 m/s limit on the hip makes a fall a 'blow-up'."""
    strict = HopperEnv(sim=env.config.sim, blowup_hip_velocity=1.0)
    strict.reset(seed=0)
    strict.sim.backend.reset_robots(np.array([0]), np.array([[1.5, *NOMINAL]]), np.zeros((1, 3)))
    steps = 1
    while not strict.step(NOMINAL)[2]:
        steps += 1
    assert steps == 11  # 1 m/s after 0.102 s of free fall: the 11th control step
    strict.close()


def test_render_without_mode_returns_none(env):
    env.reset(seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert env.render() is None
    with pytest.raises(ValueError, match="render_mode"):
        HopperEnv(render_mode="human")


def test_import_cpg_actor_registers_the_gymnasium_ids_without_loading_a_simulator():
    import subprocess
    import sys

    code = (
        "import sys, gymnasium, cpg_actor\n"
        "assert 'cpg_actor/AnymalHopper-v0' in gymnasium.registry\n"
        "assert 'cpg_actor/AnymalHopper-pybullet-v0' in gymnasium.registry\n"
        "assert 'mujoco' not in sys.modules and 'torch' not in sys.modules\n"
        "env = gymnasium.make('cpg_actor/AnymalHopper-v0')\n"
        "print(env.reset(seed=0)[0].shape)\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "(8,)"


def test_step_or_reset_after_close_is_a_clear_error():
    import gymnasium

    from cpg_actor.robots.hopper.cho2019 import CPGParameterVectorEnv
    from cpg_actor.robots.hopper.env import HopperEnv
    from cpg_actor.robots.hopper.vector import HopperVectorEnv

    for env in (HopperEnv(), HopperVectorEnv(2), CPGParameterVectorEnv(2)):
        env.reset(seed=0)
        env.close()
        env.close()  # twice is fine
        action = np.zeros(env.action_space.shape, dtype=np.float32)
        with pytest.raises(gymnasium.error.ClosedEnvironmentError, match="closed environment"):
            env.step(action)
        with pytest.raises(gymnasium.error.ClosedEnvironmentError, match="closed environment"):
            env.reset(seed=0)


def test_normalized_actions_map_minus_one_to_one_onto_the_joint_ranges():
    from cpg_actor.config import TrainConfig
    from cpg_actor.robots.hopper.env import ACTION_HIGH, ACTION_LOW
    from cpg_actor.robots.hopper.plugin import ROBOT

    assert gym.spec(ENV_ID).max_episode_steps == ROBOT.episode_steps == HopperConfig().episode_steps
    env = gym.make(ENV_ID, normalized_actions=True)
    plain = HopperEnv()
    try:
        assert env.action_space == spaces.Box(-1.0, 1.0, (2,), np.float32)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            check_env(env.unwrapped, skip_render_check=True)
        assert not [str(w.message) for w in caught]
        env.reset(seed=1)
        plain.reset(seed=1)
        for action in ([-1.0, -1.0], [1.0, 1.0], [0.2, -0.4], [3.0, -7.0]):
            info = env.step(np.array(action, dtype=np.float32))[4]
            clipped = np.clip(action, -1.0, 1.0)
            desired = ACTION_LOW + (clipped + 1.0) / 2.0 * (ACTION_HIGH - ACTION_LOW)
            assert np.allclose(info["desired_position"], desired)
            expected = plain.step(desired.astype(np.float32))
            assert np.allclose(info["hip_height"], expected[4]["hip_height"], atol=1e-6)
    finally:
        env.close()
        plain.close()
    config = TrainConfig()
    config.env.normalized_actions = True
    with pytest.raises(ValueError, match="the project's agents act on desired positions in rad"):
        config.validate()
