"""The MJX (MuJoCo XLA) hopper on JAX's CPU backend: the same robot as the MuJoCo CPU backend
(mass, statics, free fall by hand, an open-loop hopping trajectory and its reward terms within
stated tolerances), the Gymnasium and tensor contracts, exact resume, clear errors.

MJX computes in float32 with its own constraint solver, so it agrees with MuJoCo's float64 C
solver to tolerances, not bit for bit (docs/gpu.md gives the measured agreement)."""

import gymnasium as gym
import numpy as np
import pytest
import torch

from cpg_actor.robots.common import mjx_runtime as runtime
from cpg_actor.robots.common.actuator import Actuator
from cpg_actor.robots.hopper import description as robot
from cpg_actor.robots.hopper import kinematics
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.env import HopperEnv
from cpg_actor.robots.hopper.plugin import MJX_ENV_ID
from cpg_actor.robots.hopper.vector import HopperVectorEnv, make_vector_env

if not runtime.available():
    pytest.skip('the MJX backend needs pip install -e ".[mjx]"', allow_module_level=True)

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from cpg_actor.robots.hopper.mjx.vector import MjxHopperVectorEnv  # noqa: E402

G = robot.GRAVITY
HOLD = np.array(robot.NOMINAL_POSE)


def hop_action(k: int) -> np.ndarray:
    """An open-loop squat-and-extend pattern at 2 Hz that makes the hopper leave the ground."""
    phase = 2 * np.pi * 2.0 * k * 0.01
    return np.array([0.4 + 0.35 * np.sin(phase), -0.8 - 0.7 * np.sin(phase)])


def pair(num_envs=1, **overrides):
    """The same hopper on MJX and on MuJoCo (CPU), both reset with seed 0."""
    mjx = make_vector_env(num_envs, sim="mjx", **overrides)
    cpu = make_vector_env(num_envs, sim="mujoco", **overrides)
    mjx.reset(seed=0)
    cpu.reset(seed=0)
    return mjx, cpu


# -- the robot and its physics, against MuJoCo on the CPU and hand calculations ---------------
def test_same_model_as_the_cpu_backend():
    env = make_vector_env(1, sim="mjx")
    cpu = HopperVectorEnv(1, sim="mujoco")
    mj = env.dynamics.mj_model
    assert mj.body_mass[1:].sum() == pytest.approx(robot.TOTAL_MASS, rel=1e-9)
    assert mj.body_mass[1:].sum() == pytest.approx(cpu.sim.backend.total_mass(), rel=1e-9)
    np.testing.assert_allclose(mj.jnt_range, cpu.sim.backend.model.jnt_range)
    np.testing.assert_allclose(mj.body_inertia, cpu.sim.backend.model.body_inertia)
    assert mj.opt.timestep == cpu.sim.backend.model.opt.timestep
    # torque-controlled motors: MJX computes the dcmotor law itself
    assert list(mj.actuator_trntype) == [0, 0] and mj.nu == 2


def test_actuator_law_on_jax_arrays_equals_numpy():
    rng = np.random.default_rng(0)
    desired, position = rng.uniform(-1.5, 1.5, (2, 100, 2))
    velocity = rng.uniform(-30, 30, (100, 2))
    for law in ("dc-motor", "coast"):
        actuator = Actuator.from_config(HopperConfig(actuator_law=law))
        expected = actuator(desired, position, velocity)
        got = actuator(*(jnp.asarray(x, jnp.float32) for x in (desired, position, velocity)))
        # float32 against float64: within a few float32 roundings of the torques' magnitude
        scale = np.abs(expected).max()
        np.testing.assert_allclose(np.asarray(got), expected, rtol=1e-5, atol=2.5e-6 * scale)


@pytest.mark.slow
def test_free_fall_matches_the_hand_calculation():
    """Dropped 10 cm with the joints held: semi-implicit Euler free fall, x_n = x_0 - g dt^2
    n (n + 1) / 2 per substep, until the foot lands (after ~0.14 s)."""
    env, cpu = pair(reset_noise=0.0, reset_clearance=0.1)
    start = kinematics.standing_hip_height(HOLD) + 0.1
    dt = 0.001
    for step in range(1, 11):  # 0.1 s: 4.9 cm of fall, still in the air
        obs = env.step(HOLD[None])[0]
        cpu_obs = cpu.step(HOLD[None])[0]
        n = 10 * step
        assert obs[0, 6] == pytest.approx(start - G * dt**2 * n * (n + 1) / 2, abs=2e-5)
        assert obs[0, 7] == pytest.approx(-G * dt * n, abs=2e-4)
        np.testing.assert_allclose(obs[0, :2], HOLD, atol=1e-4)  # nothing bends in free fall
        np.testing.assert_allclose(obs, cpu_obs, atol=2e-4)


def test_standing_statics_agree_with_the_cpu_backend():
    """Holding the nominal pose for 1 s: the leg settles to the same sag within 1 mm."""
    env, cpu = pair(reset_noise=0.0)
    for _ in range(100):
        obs = env.step(HOLD[None])[0]
        cpu_obs = cpu.step(HOLD[None])[0]
    assert abs(obs[0, 6] - cpu_obs[0, 6]) < 1e-3
    np.testing.assert_allclose(obs[0, :2], cpu_obs[0, :2], atol=2e-3)
    assert abs(obs[0, 7]) < 1e-3  # at rest
    # it stands: the hip below the straight-leg height, above the rail's bottom stop
    assert 0.3 < obs[0, 6] < kinematics.standing_hip_height(HOLD)


def test_open_loop_hopping_trajectory_and_reward_terms_agree():
    """3 s of open-loop hopping (the foot leaves the ground by > 10 cm): the hip height stays
    within 1 cm of the CPU backend's, and every reward term summed over the run within 2 %
    (measured: 5 mm and 1 %)."""
    env, cpu = pair(reset_noise=0.0, episode_steps=1000)
    hips, cpu_hips, clearance = [], [], []
    sums = {name: np.zeros(2) for name in ("r1", "r2", "r3", "r4", "r5")}
    for k in range(300):
        obs, _, _, _, info = env.step(hop_action(k)[None])
        cpu_obs, _, _, _, cpu_info = cpu.step(hop_action(k)[None])
        hips.append(obs[0, 6])
        cpu_hips.append(cpu_obs[0, 6])
        clearance.append(cpu_info["foot_height"][0])
        for name in sums:
            sums[name] += (info["reward_terms"][name][0], cpu_info["reward_terms"][name][0])
    assert max(clearance) > 0.1
    assert np.max(np.abs(np.array(hips) - np.array(cpu_hips))) < 0.01
    for name, (mjx_sum, cpu_sum) in sums.items():
        assert mjx_sum == pytest.approx(cpu_sum, rel=0.02), name


@pytest.mark.slow
def test_apex_reward_pays_the_same_hops():
    env, cpu = pair(reset_noise=0.0, episode_steps=1000, hop_reward="apex")
    paid = np.zeros(2)
    payments = np.zeros(2)
    for k in range(200):
        r1 = env.step(hop_action(k)[None])[4]["reward_terms"]["r1"][0]
        cpu_r1 = cpu.step(hop_action(k)[None])[4]["reward_terms"]["r1"][0]
        paid += (r1, cpu_r1)
        payments += (r1 > 0, cpu_r1 > 0)
    assert payments[1] >= 2 and payments[0] == payments[1]  # one payment per hop, same hops
    assert paid[0] == pytest.approx(paid[1], rel=0.05)


@pytest.mark.slow  # a config of its own: one more compilation
def test_the_command_filter_runs_inside_the_jitted_step():
    """``command_filter`` < 1 on MJX: the desired positions follow the same recurrence as on
    the CPU backends (float32), from the reset's pose, restarting when an episode ends."""
    alpha, steps = 0.3, 4
    env = make_vector_env(2, sim="mjx", command_filter=alpha, episode_steps=steps)
    low, high = robot_limits()
    rng = np.random.default_rng(0)
    commands = rng.uniform(low, high, size=(steps + 2, 2, 2)).astype(np.float32)
    try:
        env.reset(seed=0)
        previous = np.tile(HOLD, (2, 1)).astype(np.float32)
        for k, command in enumerate(commands):
            obs, _, _, truncated, info = env.step(command)
            expected = previous + np.float32(alpha) * (command - previous)
            np.testing.assert_allclose(np.asarray(info["desired_position"]), expected, rtol=1e-6)
            previous = np.asarray(info["desired_position"])
            if k == steps - 1:  # the episode ended: the next starts from the nominal pose
                assert np.asarray(truncated).all()
                np.testing.assert_allclose(np.asarray(obs)[:, 4:6], np.tile(HOLD, (2, 1)),
                                           rtol=1e-6)  # fmt: skip
                previous = np.tile(HOLD, (2, 1)).astype(np.float32)
    finally:
        env.close()


def robot_limits():
    """The joint limits, (low, high) (rad)."""
    low = [robot.JOINT_LIMITS[j][0] for j in robot.JOINT_NAMES]
    high = [robot.JOINT_LIMITS[j][1] for j in robot.JOINT_NAMES]
    return np.array(low), np.array(high)


# -- the contracts -----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def env():
    env = make_vector_env(3, sim="mjx", episode_steps=5)
    yield env
    env.close()


@pytest.mark.slow
def test_gymnasium_face(env):
    obs, info = env.reset(seed=7)
    assert obs.shape == (3, 8) and obs.dtype == np.float32
    assert env.single_observation_space.contains(obs[0])
    assert env.robot.joint_names == ("HFE", "KFE")
    np.testing.assert_allclose(info["desired_position"], np.tile(HOLD, (3, 1)), atol=1e-7)
    for step in range(1, 6):
        obs, reward, terminated, truncated, info = env.step(np.tile(HOLD, (3, 1)))
        assert reward.shape == (3,) and not terminated.any()
        assert truncated.all() == (step == 5)
        hop = info["episode_metrics"]["hop_height"]
        assert np.isnan(hop).all() != (step == 5)
    # SAME_STEP autoreset: the new episode's first observation, the last one in final_obs
    assert info["_final_obs"].all()
    np.testing.assert_allclose(obs[:, 4:6], np.tile(HOLD, (3, 1)), atol=1e-7)
    assert not np.allclose(obs[:, :2], info["final_obs"][:, :2])
    assert (hop >= 0).all()


def test_seeds_follow_gymnasium_conventions(env):
    first = env.reset(seed=11)[0]
    assert np.array_equal(first, env.reset(seed=11)[0])
    assert not np.allclose(first, env.reset(seed=12)[0])
    # env i of seed s is seeded s + i
    shifted = env.reset(seed=[12, 13, 14])[0]
    np.testing.assert_array_equal(shifted[:2], first[1:])
    joint_noise = first[:, :2] - HOLD
    assert np.all(np.abs(joint_noise) <= 0.1 + 1e-6) and np.ptp(joint_noise[:, 0]) > 0


def test_tensor_face_passes_tensors_through_dlpack(env):
    obs, _ = env.reset_tensors(seed=0)
    assert isinstance(obs, torch.Tensor) and obs.device == env.device
    x = jax.device_put(jnp.arange(4.0), env.jax_device)
    assert env._to_torch(x).data_ptr() == x.unsafe_buffer_pointer()  # no copy
    t = torch.arange(4.0, device=env.device)  # on the env's device (a GPU on a GPU machine)
    assert env._to_jax(t).unsafe_buffer_pointer() == t.data_ptr()
    step = env.step_tensors(torch.tensor(np.tile(HOLD, (3, 1)), dtype=torch.float32))
    assert step.obs.dtype == torch.float32 and step.terminated.dtype == torch.bool
    assert set(step.reward_terms) == {"r1", "r2", "r3", "r4", "r5"}
    assert torch.allclose(step.reward, sum(step.reward_terms.values()), atol=1e-6)


def test_resume_from_a_saved_state_is_exact():
    rng = np.random.default_rng(0)
    actions = [HOLD + 0.3 * rng.standard_normal((3, 2)) for _ in range(24)]
    env = make_vector_env(3, sim="mjx", episode_steps=7)
    env.reset(seed=5)
    for action in actions[:8]:
        env.step(action)
    state = env.get_state()
    expected = [env.step(action) for action in actions[8:]]
    other = make_vector_env(3, sim="mjx", episode_steps=7)
    other.set_state(state)
    for action, (obs, reward, _, truncated, _) in zip(actions[8:], expected, strict=True):
        step = other.step(action)
        assert np.array_equal(step[0], obs) and np.array_equal(step[1], reward)
        assert np.array_equal(step[3], truncated)
    with pytest.raises(ValueError, match="has 3 envs, this env 2"):
        make_vector_env(2, sim="mjx").set_state(state)
    with pytest.raises(ValueError, match="not a state of MjxHopperVectorEnv"):
        other.set_state({"simulation": {}})


def test_episode_length_and_reset_numbers_share_one_compilation(env):
    """Configs that differ only in episode length, reset noise and clearance share the jitted
    functions (they are values, not compiled constants) and still act on their own numbers."""
    short = make_vector_env(3, sim="mjx", episode_steps=2, reset_noise=0.0, reset_clearance=0.05)
    assert short.dynamics is env.dynamics
    obs, _ = short.reset(seed=7)
    np.testing.assert_allclose(obs[:, :2], np.tile(HOLD, (3, 1)), atol=1e-6)  # no noise
    hip = kinematics.standing_hip_height(HOLD) + 0.05
    np.testing.assert_allclose(obs[:, 6], hip, atol=1e-6)
    assert not short.step(np.tile(HOLD, (3, 1)))[3].any()
    assert short.step(np.tile(HOLD, (3, 1)))[3].all()  # truncated after 2 steps, not 5
    noisy = env.reset(seed=7)[0]
    assert np.abs(noisy[:, :2] - HOLD).max() > 0.01 and np.ptp(noisy[:, 6]) > 0  # noise 0.1
    short.close()


def test_a_blown_up_robot_is_terminated_with_finite_numbers(env):
    env.reset(seed=0)
    state = env.get_state()
    state["mjx"]["qvel"][1] = torch.tensor([0.0, float("nan"), 1e9])
    env.set_state(state)
    obs, reward, terminated, truncated, info = env.step(np.tile(HOLD, (3, 1)))
    assert terminated.tolist() == [False, True, False] and not truncated[1]
    assert np.isfinite(obs).all() and np.isfinite(info["final_obs"]).all()
    assert reward[1] == 0.0 and np.isfinite(reward).all()
    obs, *_ = env.step(np.tile(HOLD, (3, 1)))  # the new episode runs normally
    assert np.isfinite(obs).all()


def test_bad_input_gets_a_clear_error(env):
    env.reset(seed=0)
    with pytest.raises(ValueError, match="finite"):
        env.step(np.full((3, 2), np.nan))
    with pytest.raises(ValueError, match=r"shape \(3, 2\)"):
        env.step(np.zeros((2, 2)))
    with pytest.raises(ValueError, match="finite"):
        env.step_tensors(torch.full((3, 2), float("inf")))
    with pytest.raises(ValueError, match=r"shape \(3, 2\)"):
        env.step_tensors(torch.zeros(3))
    # unchecked (the trainer checks its actions once per rollout): the robot blows up, is
    # terminated with finite numbers and starts afresh
    nan = torch.tensor([[float("nan")] * 2, HOLD.tolist(), HOLD.tolist()], dtype=torch.float32)
    out = env.step_tensors(nan, check_finite=False)
    assert out.terminated.tolist() == [True, False, False]
    assert torch.isfinite(out.obs).all() and torch.isfinite(out.reward).all()
    with pytest.raises(ValueError, match="num_envs"):
        MjxHopperVectorEnv(0)
    with pytest.raises(ValueError, match="make_vector_env"):
        HopperEnv(sim="mjx")
    with pytest.raises(ValueError, match="sim must be one of"):
        HopperConfig(sim="mjc")
    fresh = make_vector_env(3, sim="mjx", episode_steps=5)
    with pytest.raises(RuntimeError, match="reset"):
        fresh.step(np.zeros((3, 2)))
    fresh.close()
    with pytest.raises(gym.error.ClosedEnvironmentError):
        fresh.reset(seed=0)


def test_registered_for_make_vec():
    env = gym.make_vec(MJX_ENV_ID, num_envs=2, vectorization_mode="vector_entry_point")
    try:
        assert isinstance(env, MjxHopperVectorEnv)
        assert env.reset(seed=0)[0].shape == (2, 8)
    finally:
        env.close()
    with pytest.raises(ValueError, match="make_vec"):
        gym.make(MJX_ENV_ID)


def test_jax_does_not_preallocate_the_gpu():
    import os

    assert os.environ["XLA_PYTHON_CLIENT_PREALLOCATE"] == "false"
    assert jnp.zeros(1).dtype == jnp.float32  # no x64: float32 physics


def test_render_frame_draws_the_mjx_state(env):
    env.reset(seed=0)
    try:
        frame = env.render_frame(1)
    except Exception as error:  # no OpenGL on this machine: MuJoCo's renderer cannot start
        if "GL" not in str(error):
            raise
        pytest.skip(f"no MuJoCo GL context: {error}")
    assert frame.shape == (480, 640, 3) and frame.dtype == np.uint8 and frame.std() > 10
    with pytest.raises(ValueError, match="index must be in 0..2"):
        env.render_frame(3)


def test_the_cho2019_wrapper_keeps_the_tensor_face_and_its_numbers():
    from cpg_actor.robots.hopper.cho2019 import CPGParameterVectorEnv

    assert not hasattr(CPGParameterVectorEnv(1, config={"sim": "mujoco"}), "step_tensors")
    tensors = CPGParameterVectorEnv(make_vector_env(3, sim="mjx", episode_steps=5))
    arrays = CPGParameterVectorEnv(make_vector_env(3, sim="mjx", episode_steps=5))
    obs, _ = tensors.reset_tensors(seed=1)
    np.testing.assert_array_equal(obs.cpu().numpy(), arrays.reset(seed=1)[0])
    rng = np.random.default_rng(0)
    for _ in range(7):  # across the end of the 5-step episodes
        action = rng.uniform(-1.0, 1.0, (3, 5)).astype(np.float32)
        out = tensors.step_tensors(torch.from_numpy(action))
        obs, reward, terminated, truncated, info = arrays.step(action)
        np.testing.assert_array_equal(out.obs.cpu().numpy(), obs)
        np.testing.assert_array_equal(out.reward.cpu().numpy(), reward)
        np.testing.assert_array_equal(out.truncated.cpu().numpy(), truncated)
        np.testing.assert_array_equal(out.final_obs.cpu().numpy(), info["final_obs"])
        np.testing.assert_array_equal(out.info["theta_dot"].cpu().numpy(), info["theta_dot"])
