"""The ANYmal B quadruped: its description, standing statics, the locomotion env's API and
episode ends, and the open-loop trot of the CPG preset walking for a whole episode."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from cpg_actor.robots.anymal import description as robot
from cpg_actor.robots.anymal.gaits import ANYMAL_GAITS
from cpg_actor.robots.anymal.plugin import ENV_ID as ANYMAL_ENV_ID
from cpg_actor.robots.anymal.vector import ANYMAL, AnymalVectorEnv
from cpg_actor.robots.common.mujoco_runtime import mujoco
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.common.quadruped.vector import load_model
from cpg_actor.tasks import velocity as task

NOMINAL = np.array(robot.NOMINAL_POSE)


def test_masses_and_mirrored_legs():
    model = load_model(ANYMAL, QuadrupedConfig())
    assert model.body_mass.sum() == pytest.approx(16.793507758 + 4 * 3.40697, abs=1e-4)
    assert robot.TOTAL_MASS == pytest.approx(30.4214, abs=1e-4)
    # mirror images: every leg has the same mass; LF and RF are mirrored in y
    masses = {leg: sum(b.mass for b, _, _ in robot.LEG_BODIES[leg]) for leg in robot.LEGS}
    assert len(set(masses.values())) == 1
    for (lf, o_lf, _), (rf, o_rf, _) in zip(robot.LEG_BODIES["LF"], robot.LEG_BODIES["RF"],
                                            strict=True):  # fmt: skip
        assert lf.com[1] == pytest.approx(-rf.com[1]) and o_lf[1] == pytest.approx(-o_rf[1])
    for name in robot.JOINT_NAMES:
        lo, hi = model.jnt_range[model.joint(name).id]
        assert (lo, hi) == pytest.approx(robot.JOINT_LIMITS[name])
    assert model.nu == 12 and model.nq == 19


def test_standing_statics_carry_the_weight_level_and_symmetric():
    """Two seconds in the nominal pose: the feet carry m g, the base stays level at about the
    task's target height, left and right joints need mirrored torques within the limits."""
    env = AnymalVectorEnv(1, {"reset_noise": 0.0})
    env.reset(seed=0)
    for _ in range(100):
        obs, *_ = env.step(NOMINAL[None])
    model, data = env.model, env._data
    mujoco.mj_setState(model, data, env._state[0], mujoco.mjtState.mjSTATE_FULLPHYSICS.value)
    data.ctrl[:] = NOMINAL
    mujoco.mj_forward(model, data)
    normal = 0.0
    force = np.zeros(6)
    for i in range(data.ncon):
        mujoco.mj_contactForce(model, data, i, force)
        normal += force[0]
    assert data.ncon == 4  # the four feet, nothing else
    assert normal == pytest.approx(robot.TOTAL_MASS * robot.GRAVITY, rel=0.01)
    height = env.qpos[0, 2]
    assert abs(height - env.config.base_height_target) < 0.01
    gravity = task.projected_gravity(env.qpos[:, 3:7])[0]
    assert np.degrees(np.arccos(-gravity[2])) < 0.5
    torque = env._sensors[0, -1, :12].reshape(4, 3)  # LF, RF, LH, RH x (HAA, HFE, KFE)
    assert np.abs(torque).max() < 12.0  # well inside 40 N m
    assert torque[0, 1:] == pytest.approx(torque[1, 1:], abs=0.3)  # left = right (HFE, KFE)
    assert torque[0, 1:] == pytest.approx(-torque[2, 1:], abs=1.0)  # hind mirrors front


def test_env_api_spaces_seeds_and_errors():
    env = AnymalVectorEnv(3)
    obs, info = env.reset(seed=7)
    assert obs.shape == (3, len(ANYMAL.observation_names)) == (3, 45) and obs.dtype == np.float32
    assert env.single_action_space.shape == (12,)
    assert np.all((info["command"][:, 0] >= 0) & (info["command"][:, 0] <= 1))
    again, _ = AnymalVectorEnv(3).reset(seed=7)
    assert np.array_equal(obs, again)  # same seed, same start
    other, _ = AnymalVectorEnv(3).reset(seed=8)
    assert not np.array_equal(obs[0], other[0])
    obs, reward, terminated, truncated, info = env.step(np.tile(NOMINAL, (3, 1)))
    assert reward.shape == (3,) and np.isfinite(reward).all()
    assert set(info["reward_terms"]) == set(QuadrupedConfig().reward_scales)
    assert reward == pytest.approx(sum(info["reward_terms"].values()))
    with pytest.raises(ValueError, match=r"shape \(3, 12\)"):
        env.step(np.zeros((3, 2)))
    with pytest.raises(ValueError, match="finite"):
        env.step(np.full((3, 12), np.nan))
    with pytest.raises(ValueError, match="unknown QuadrupedConfig fields"):
        AnymalVectorEnv(1, {"kpp": 1.0})
    with pytest.raises(ValueError, match="unknown reward terms"):
        AnymalVectorEnv(1, {"reward_scales": {"speed": 1.0}})
    env.close()
    with pytest.raises(gym.error.ClosedEnvironmentError):
        env.step(np.tile(NOMINAL, (3, 1)))
    vec = gym.make_vec(ANYMAL_ENV_ID, num_envs=2)
    assert isinstance(vec, AnymalVectorEnv) and vec.reset(seed=0)[0].shape == (2, 45)


def test_lateral_and_yaw_commands_are_drawn_in_their_ranges_and_tracked():
    """0 by default; with ranges, each env draws its own, the forward commands and the reset
    noise unchanged, and the tracking terms compare the base's velocities with them."""
    plain, _ = AnymalVectorEnv(4).reset(seed=5)
    env = AnymalVectorEnv(4, {"lateral_range": [-0.3, 0.3], "yaw_range": [-1.0, 1.0]})
    obs, info = env.reset(seed=5)
    assert np.array_equal(plain[:, :3], obs[:, :3]) and np.array_equal(plain[:, 6], obs[:, 6])
    assert np.array_equal(plain[:, 9:21], obs[:, 9:21])  # the same reset noise
    assert np.all(plain[:, 7:9] == 0.0)
    lateral, yaw = info["command"][:, 1], info["command"][:, 2]
    assert np.allclose(obs[:, 7], lateral) and np.allclose(obs[:, 8], yaw)  # float32
    assert np.all(np.abs(lateral) <= 0.3) and np.all(np.abs(yaw) <= 1.0)
    assert len(set(lateral.tolist())) == 4 and len(set(yaw.tolist())) == 4
    obs, _, _, _, step = env.step(np.tile(NOMINAL, (4, 1)))
    # the yaw kernel exp(-(w_z - yaw command)^2 / sigma), w_z the gyro's (observation 2)
    yaw_rate = obs[:, 2].astype(np.float64)
    kernel = np.exp(-((yaw_rate - yaw) ** 2) / env.config.tracking_sigma)
    expected = kernel * env.config.reward_scales["tracking_ang_vel"] * env.config.control_dt
    assert np.allclose(step["reward_terms"]["tracking_ang_vel"], expected, rtol=1e-5)
    with pytest.raises(ValueError, match="yaw_range must be"):
        AnymalVectorEnv(1, {"yaw_range": [1.0, -1.0]})
    env.close()


def test_saved_state_continues_exactly():
    rng = np.random.default_rng(0)
    actions = [NOMINAL + 0.2 * rng.standard_normal((2, 12)) for _ in range(30)]
    env = AnymalVectorEnv(2, {"episode_seconds": 0.3})  # 15-step episodes: resets included
    env.reset(seed=3)
    for a in actions[:10]:
        env.step(a)
    state = env.get_state()
    expected = [env.step(a) for a in actions[10:]]
    other = AnymalVectorEnv(2, {"episode_seconds": 0.3})
    other.set_state(state)
    for a, (obs, reward, terminated, truncated, _) in zip(actions[10:], expected, strict=True):
        step = other.step(a)
        assert np.array_equal(step[0], obs) and np.array_equal(step[1], reward)
        assert np.array_equal(step[2], terminated) and np.array_equal(step[3], truncated)
    with pytest.raises(ValueError, match="not a state of AnymalVectorEnv"):
        other.set_state({"simulation": {}})
    # a state saved before the foot-slip counters existed: they restart at 0, the rest exact
    old = {"anymal": {k: v for k, v in state["anymal"].items()
                      if k not in ("slip_sum", "planted_steps")}}  # fmt: skip
    other.set_state(old)
    episode = other.episode
    assert np.array_equal(episode.slip_sum, [0.0, 0.0]) and episode.planted_steps.dtype == np.int64
    assert np.array_equal(other.step(actions[10])[0], expected[0][0])


def test_episodes_end_by_falling_or_by_time_with_their_metrics():
    env = AnymalVectorEnv(2, {"episode_seconds": 0.2})  # 10 steps
    env.reset(seed=0)
    env.qpos[1, 3:7] = (np.cos(0.7), np.sin(0.7), 0.0, 0.0)  # rolled 1.4 rad: fallen
    obs, reward, terminated, truncated, info = env.step(np.tile(NOMINAL, (2, 1)))
    assert terminated.tolist() == [False, True] and not truncated.any()
    assert info["episode_metrics"]["fell"][1] == 1.0
    assert np.isnan(info["episode_metrics"]["fell"][0])
    assert info["_final_obs"].tolist() == [False, True]
    assert not np.array_equal(obs[1], info["final_obs"][1])  # already the next episode
    for _ in range(9):
        obs, reward, terminated, truncated, info = env.step(np.tile(NOMINAL, (2, 1)))
    assert truncated.tolist() == [True, False]  # env 0 after 10 steps, env 1 restarted
    assert info["episode_metrics"]["episode_seconds"][0] == pytest.approx(0.2)
    assert info["episode_metrics"]["fell"][0] == 0.0


def test_planted_slip_is_the_horizontal_speed_of_feet_on_the_ground_at_both_ends():
    before = np.zeros((1, 4, 2))
    now = np.array([[[0.003, 0.004], [0.01, 0.0], [0.01, 0.0], [0.0, 0.0]]])
    contact = np.array([[True, True, False, True]])
    in_contact = np.array([[True, False, True, True]])
    slip, planted = task.planted_slip(now, before, contact, in_contact, 0.02)
    assert planted.tolist() == [[True, False, False, True]]  # lifting or landing: not planted
    assert np.allclose(slip, [[0.25, 0.0, 0.0, 0.0]])  # 5 mm in 20 ms


def test_a_robot_pushed_along_its_planted_feet_is_charged_for_the_slip():
    """Standing still, once settled (0.4 s), the planted feet barely move (under 5 mm/s).
    Moving the whole robot 1 cm forward between two steps drags its four planted feet 1 cm in
    one 20 ms step: 0.5 m/s each, so the feet_slip term is 4 x 0.5^2 = 1 (times its scale and
    dt), and the episode's foot_slip metric (the mean over its 30 steps x 4 feet) gains
    0.5 / 30 m/s."""
    env = AnymalVectorEnv(1, {"episode_seconds": 0.6, "reset_noise": 0.0,
                              "reward_scales": {"feet_slip": -1.0}})  # fmt: skip
    env.reset(seed=0)
    hold, dt = NOMINAL[None, :], env.config.control_dt
    speeds = []
    for step in range(30):
        if step == 20:
            env.qpos[0, 0] += 0.01
        _, _, _, truncated, info = env.step(hold)
        assert info["contact"].all()
        # the root mean square over the feet (they slide alike: equal when pushed)
        speeds.append(np.sqrt(info["reward_terms"]["feet_slip"][0] / -dt / 4))
    assert max([speeds[19], *speeds[21:]]) < 0.005  # settled
    assert speeds[20] == pytest.approx(0.5, rel=0.02)  # pushed
    assert truncated[0]
    assert info["episode_metrics"]["foot_slip"][0] <= np.mean(speeds)  # mean <= RMS
    # the settling steps add about 5 mm/s to the mean
    assert 0.5 / 30 < info["episode_metrics"]["foot_slip"][0] < 0.5 / 30 + 0.01
    env.close()


def _open_loop_trot(command: float, n: int = 4) -> dict:
    """The trot preset, no learning, ``n`` robots with reset noise, its drive d set by the
    forward ``command``: the metrics of one 20 s episode (asserting it never falls)."""
    env = AnymalVectorEnv(n, {"command_range": (command, command)})
    env.reset(seed=0)
    steps, dt = env.config.episode_steps, env.config.control_dt
    ended = None
    trot = ANYMAL_GAITS.open_loop_positions("trot", dt, robot.NOMINAL_POSE, n, steps, command)
    for action in trot.numpy():
        _, _, terminated, truncated, info = env.step(action)
        assert not terminated.any()
        if truncated.any():
            ended = info["episode_metrics"]
    env.close()
    assert ended is not None
    assert np.all(ended["fell"] == 0.0) and np.all(ended["episode_seconds"] == 20.0)
    return ended


def test_the_open_loop_trot_walks_a_whole_episode_without_falling_faster_with_the_drive():
    """20 s (1,000 steps) with no fall at the drives of a 0 and a 1 m/s command; the drive
    (eq. 3: longer, slightly faster steps) makes the body walk forward (0.15-0.46 m/s; it
    steps nearly in place at d = 0)."""
    still, walking = _open_loop_trot(0.0), _open_loop_trot(1.0)
    assert np.all(np.abs(still["forward_speed"]) < 0.15)
    # 0.15-0.46 m/s: the robots settle into a faster or a slower stepping mode
    assert np.all(walking["forward_speed"] > 0.1) and walking["forward_speed"].mean() > 0.2
    assert np.all(walking["forward_speed"] > still["forward_speed"] + 0.1)
    # mechanical work over weight x distance along x: positive and finite (7 to 24 here: the
    # open-loop trot drifts in heading, so the faster robots get less far along x)
    ended = walking
    assert np.all((ended["cost_of_transport"] > 0.05) & (ended["cost_of_transport"] < 50))
