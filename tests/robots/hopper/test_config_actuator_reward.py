"""HopperConfig validation, the actuator law, and each reward term on constructed states."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cpg_actor.robots.common.actuator import Actuator
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.env import HopperEnv
from cpg_actor.robots.hopper.reward import REWARD_TERMS, reward_terms, total_reward

# -- config ---------------------------------------------------------------------------------


def test_defaults_and_control_dt():
    config = HopperConfig()
    assert config.sim == "mujoco"
    assert config.control_dt == pytest.approx(0.01)
    assert config.episode_steps * config.control_dt == pytest.approx(5.0)
    assert (config.torque_limit, config.velocity_limit) == (40.0, 15.0)
    assert config.c1 >= 0 and all(c <= 0 for c in config.reward_weights[1:])


def test_from_dict_round_trip_and_int_coercion():
    config = HopperConfig(kp=100.0, sim="pybullet")
    assert HopperConfig.from_dict(config.to_dict()) == config
    assert HopperConfig.from_dict({"kp": 90}).kp == 90.0  # YAML writes 90.0 as 90
    assert isinstance(HopperConfig.from_dict({"kp": 90}).kp, float)


def test_unknown_keys_are_listed_with_the_accepted_ones():
    with pytest.raises(ValueError) as error:
        HopperConfig.from_dict({"kp": 80.0, "kpp": 1, "gains": 2})
    message = str(error.value)
    assert "gains, kpp" in message
    for field in dataclasses.fields(HopperConfig):
        assert field.name in message


@pytest.mark.parametrize(
    "changes, fragment",
    [
        ({"c1": -1.0}, "c1 must be >= 0"),
        ({"c2": 0.5}, "c2 must be <= 0"),
        ({"c3": 1e-3}, "c3 must be <= 0"),
        ({"c4": 1.0}, "c4 must be <= 0"),
        ({"c5": 0.1}, "c5 must be <= 0"),
        ({"sim": "gazebo"}, "sim must be one of"),
        ({"physics_dt": 0.0}, "physics_dt must be > 0"),
        ({"physics_dt": 0.01}, "physics_dt must be <= 0.005"),
        ({"decimation": 2.5}, "decimation must be an integer"),
        ({"kp": "high"}, "kp must be a number"),
        ({"kd": float("nan")}, "kd must be finite"),
        ({"kd": -1.0}, "kd must be >= 0"),
        ({"saturation_torque": 20.0}, "saturation_torque"),
        ({"episode_steps": True}, "episode_steps must be an integer"),
    ],
)
def test_bad_values_are_clear_errors(changes, fragment):
    with pytest.raises(ValueError, match=fragment):
        HopperConfig(**changes)
    with pytest.raises(ValueError, match=fragment):
        HopperEnv(**changes)  # before any simulator is created


# -- actuator -------------------------------------------------------------------------------


def test_pd_law_inside_the_limits():
    actuator = Actuator.from_config(HopperConfig(kp=80.0, kd=2.0))
    tau = actuator(np.array([0.5, -0.7]), np.array([0.4, -0.8]), np.array([1.0, -2.0]))
    np.testing.assert_allclose(tau, [80 * 0.1 - 2 * 1.0, 80 * 0.1 + 2 * 2.0])


def test_torque_is_clipped_to_40_nm():
    actuator = Actuator.from_config(HopperConfig())
    tau = actuator(np.array([[2.0, -2.0]]), np.zeros((1, 2)), np.zeros((1, 2)))
    np.testing.assert_allclose(tau, [[40.0, -40.0]])


def test_torque_speed_curve_models_the_velocity_limit():
    actuator = Actuator.from_config(HopperConfig())  # tau_sat 80, v_max 15, tau_max 40
    push = np.array([10.0])  # a huge position error: the PD law asks for +800 N m
    # 80 (1 - v / 15), at most 40: full torque up to 7.5 rad/s, none at 15, braking beyond
    for velocity, expected in [
        (0.0, 40.0), (7.5, 40.0), (11.25, 20.0), (15.0, 0.0), (20.0, -80 / 3), (30.0, -40.0)
    ]:  # fmt: skip
        tau = actuator(push, np.zeros(1), np.array([velocity]))
        assert tau[0] == pytest.approx(expected), velocity
    # moving the other way, the same push is braking: never limited below 40 N m
    for velocity in (-5.0, -15.0, -30.0):
        assert actuator(push, np.zeros(1), np.array([velocity]))[0] == pytest.approx(40.0)
    # beyond the limit the back-EMF brakes the joint whatever the command
    lower, upper = actuator.torque_bounds(np.array([20.0]))
    assert upper[0] == pytest.approx(-80 / 3) and lower[0] == -40.0
    # symmetric for the negative direction
    lower, upper = actuator.torque_bounds(np.array([-11.25]))
    assert (lower[0], upper[0]) == (-20.0, 40.0)


def test_coast_law_never_brakes_beyond_the_velocity_limit():
    """``actuator_law="coast"`` (the law before 26 Nov 2026): the torque-speed line is clipped
    at 0, so past v_max the drive gives nothing in the direction of motion but is not braked."""
    actuator = Actuator.from_config(HopperConfig(actuator_law="coast"))
    push = np.array([10.0])
    for velocity, expected in [(7.5, 40.0), (11.25, 20.0), (15.0, 0.0), (20.0, 0.0), (30.0, 0.0)]:
        assert actuator(push, np.zeros(1), np.array([velocity]))[0] == pytest.approx(expected)
    assert actuator(-push, np.zeros(1), np.array([-20.0]))[0] == 0.0
    assert actuator(-push, np.zeros(1), np.array([20.0]))[0] == -40.0  # braking is still there
    lower, upper = actuator.torque_bounds(np.array([20.0, -20.0, 3.0]))
    np.testing.assert_array_equal(upper, [0.0, 40.0, 40.0])
    np.testing.assert_array_equal(lower, [-40.0, 0.0, -40.0])
    with pytest.raises(ValueError, match="actuator_law must be one of dc-motor, coast"):
        HopperConfig(actuator_law="ideal")


@pytest.mark.parametrize("overrides", [{}, {"kp": 300.0, "kd": 5.0, "saturation_torque": 60.0}])
def test_mujoco_dcmotor_actuator_is_the_same_law(overrides):
    """The MuJoCo backend runs the law inside the simulator (a ``dcmotor`` actuator): at random
    positions, velocities (past the velocity limit too) and commands, the force MuJoCo
    computes equals :class:`Actuator`'s to rounding."""
    import mujoco

    from cpg_actor.robots.hopper.backends.mujoco_backend import load_model

    config = HopperConfig(**overrides)
    actuator = Actuator.from_config(config)
    model = load_model(config.physics_dt, config.foot_friction, actuator)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(0)
    for _ in range(500):
        data.qpos[1:3] = rng.uniform(-1.5, 1.5, 2)
        data.qvel[1:3] = rng.uniform(-40.0, 40.0, 2)
        data.ctrl[:] = rng.uniform(-2.0, 2.0, 2)
        mujoco.mj_forward(model, data)
        expected = actuator(data.ctrl, data.qpos[1:3], data.qvel[1:3])
        np.testing.assert_allclose(data.actuator_force, expected, rtol=0, atol=1e-9)
        np.testing.assert_allclose(data.sensordata, expected, rtol=0, atol=1e-9)
        np.testing.assert_allclose(data.qfrc_actuator[1:3], expected, rtol=0, atol=1e-9)


def test_actuator_is_elementwise_on_batches():
    actuator = Actuator.from_config(HopperConfig())
    rng = np.random.default_rng(0)
    desired, pos, vel = rng.normal(size=(3, 64, 2))
    vel = 20.0 * vel  # reach the torque-speed limits too
    batch = actuator(desired, pos, vel)
    rows = np.stack([actuator(d, p, v) for d, p, v in zip(desired, pos, vel, strict=True)])
    np.testing.assert_array_equal(batch, rows)


# -- reward ---------------------------------------------------------------------------------


def test_each_reward_term_on_a_constructed_state():
    weights = (2.0, -3.0, -0.5, -0.01, -4.0)
    terms = reward_terms(
        weights,
        hip_velocity=np.array([0.5, -0.5]),
        desired_position=np.array([[0.5, -0.7], [0.4, -0.8]]),
        measured_position=np.array([[0.4, -0.9], [0.4, -0.8]]),
        joint_velocity=np.array([[1.0, -2.0], [0.0, 3.0]]),
        joint_torque=np.array([[10.0, -20.0], [0.0, 0.0]]),
        foot_velocity_xy=np.array([[0.3, 0.4], [-0.1, 0.0]]),
    )
    assert tuple(terms) == REWARD_TERMS
    np.testing.assert_allclose(terms["r1"], [(2.0 * 0.5) ** 2, 0.0])  # only upwards counts
    np.testing.assert_allclose(terms["r2"], [-3.0 * (0.1**2 + 0.2**2), 0.0])
    np.testing.assert_allclose(terms["r3"], [-0.5 * (1 + 4), -0.5 * 9])
    np.testing.assert_allclose(terms["r4"], [-0.01 * (100 + 400), 0.0])
    np.testing.assert_allclose(terms["r5"], [-4.0 * 0.5, -4.0 * 0.1])
    np.testing.assert_allclose(total_reward(terms), sum(terms[k] for k in REWARD_TERMS), rtol=1e-12)


def test_penalties_are_never_positive_with_valid_weights():
    rng = np.random.default_rng(1)
    terms = reward_terms(
        HopperConfig().reward_weights, rng.normal(size=100), *rng.normal(size=(5, 100, 2))
    )
    assert (terms["r1"] >= 0).all()
    for name in ("r2", "r3", "r4", "r5"):
        assert (terms[name] <= 0).all(), name


def episode_return(env, amplitude, frequency=2.0, steps=200):
    env.reset(seed=0)
    total, terms = 0.0, dict.fromkeys(REWARD_TERMS, 0.0)
    for i in range(steps):
        s = np.sin(2 * np.pi * frequency * i * env.config.control_dt)
        _, reward, terminated, _, info = env.step(
            np.array([0.4 + amplitude * s, -0.8 - 2 * amplitude * s])
        )
        assert not terminated
        total += reward
        for name in REWARD_TERMS:
            terms[name] += info["reward_terms"][name]
    return total, terms


def test_default_weights_make_hopping_beat_standing_still():
    """2 s of a 2 Hz squat-and-extend (short hops) against holding the nominal pose."""
    env = HopperEnv()
    standing, _ = episode_return(env, amplitude=0.0)
    small, _ = episode_return(env, amplitude=0.15)  # the CPG preset's amplitudes
    hopping, terms = episode_return(env, amplitude=0.3)
    env.close()
    assert standing < 0.0 < small < hopping
    assert hopping > 50.0
    penalties = -(terms["r2"] + terms["r3"] + terms["r4"] + terms["r5"])
    assert 0.05 * terms["r1"] < penalties < 0.5 * terms["r1"]  # penalties shape, r1 drives


def launched(sim, lift, v0, config_changes=None):
    """A hopper simulation with the leg in the nominal pose, its foot `lift` above the ground,
    moving up at v0."""
    from cpg_actor.robots.hopper import kinematics
    from cpg_actor.robots.hopper.simulation import HopperSimulation
    from cpg_actor.robots.hopper.task import NOMINAL_POSE

    config = HopperConfig(sim=sim, hop_reward="apex", apex_weight=100.0, **(config_changes or {}))
    simulation = HopperSimulation(config, 1)
    standing = float(kinematics.standing_hip_height(NOMINAL_POSE))
    qpos = np.array([[standing + lift, *NOMINAL_POSE]])
    simulation.backend.reset_robots(np.array([0]), qpos, np.array([[v0, 0.0, 0.0]]))
    com = standing + lift + float(kinematics.com_height_offset(NOMINAL_POSE))
    return simulation, com


@pytest.mark.parametrize("sim", ["mujoco", "pybullet"])
def test_apex_reward_pays_the_ballistic_apex_height_once(sim):
    """Launched upward at v0, the centre of mass flies to com0 + v0^2 / 2g (hand calculation,
    frictionless rail): the apex reward pays that height above the highest standing centre of
    mass, once, at t = v0 / g, and nothing on the way up or down."""
    from cpg_actor.robots.hopper import kinematics
    from cpg_actor.robots.hopper.task import NOMINAL_POSE

    simulation, com0 = launched(sim, lift=0.1, v0=1.5)
    r1 = [simulation.step(NOMINAL_POSE[None]).reward_terms["r1"][0] for _ in range(25)]
    expected = 100.0 * (com0 + 1.5**2 / (2 * 9.81) - kinematics.highest_standing_com())
    simulation.close()
    paid = [r for r in r1 if r != 0.0]
    assert len(paid) == 1 and expected > 5.0
    assert paid[0] == pytest.approx(expected, abs=100.0 * 0.003)
    assert r1.index(paid[0]) in (14, 15)  # t = v0 / g = 0.153 s: the 15th or 16th step


def test_apex_reward_pays_once_per_flight_however_the_leg_swings():
    """Folding and swinging the leg in flight moves the hip up and down many times, but not
    the centre of mass: one payment per flight."""
    from cpg_actor.robots.hopper.task import NOMINAL_POSE

    simulation, _ = launched("mujoco", lift=0.15, v0=2.0)
    r1, hip_velocity = [], []
    for t in range(30):  # the knee swings +-0.5 rad at 12.5 Hz while the leg flies
        knee = NOMINAL_POSE[1] + (0.5 if (t // 4) % 2 else -0.5)
        result = simulation.step(np.array([[NOMINAL_POSE[0], knee]]))
        r1.append(result.reward_terms["r1"][0])
        hip_velocity.append(simulation.backend.qvel[0, 0])
    simulation.close()
    turns = np.sum((np.array(hip_velocity[:-1]) > 0) & (np.array(hip_velocity[1:]) <= 0))
    assert turns >= 2  # the hip's velocity turned down more than once
    assert sum(r != 0.0 for r in r1) == 1


def test_apex_reward_pays_nothing_for_raising_the_hip_by_extending_the_leg():
    """Standing up slowly from the nominal pose raises the hip by centimetres with the foot
    on the ground: eq. 4's r1 pays for the upward hip speed, the apex reward pays nothing."""
    from cpg_actor.robots.hopper.task import NOMINAL_POSE

    totals = {}
    for hop_reward in ("hip-velocity", "apex"):
        env = HopperEnv(HopperConfig(hop_reward=hop_reward, reset_noise=0.0))
        env.reset(seed=0)
        start = env.unwrapped.sim.backend.hip_height[0]
        totals[hop_reward] = 0.0
        for t in range(150):  # the knee straightens from -0.8 to -0.3 rad over 1.2 s
            knee = NOMINAL_POSE[1] + 0.5 * min(1.0, t / 120)
            *_, info = env.step(np.array([NOMINAL_POSE[0], knee]))
            totals[hop_reward] += info["reward_terms"]["r1"]
        risen = env.unwrapped.sim.backend.hip_height[0] - start
        env.close()
    assert risen > 0.03
    assert totals["hip-velocity"] > 0.0 and totals["apex"] == 0.0


def test_hop_reward_is_checked():
    with pytest.raises(ValueError, match=r"hop_reward must be one of \('hip-velocity', 'apex'\)"):
        HopperConfig(hop_reward="height")
    with pytest.raises(ValueError, match="apex_weight must be >= 0"):
        HopperConfig(apex_weight=-1.0)


def test_batched_centre_of_mass_agrees_with_the_per_link_one():
    from cpg_actor.robots.hopper import description as robot
    from cpg_actor.robots.hopper import kinematics

    poses = np.random.default_rng(0).uniform([-0.5, -1.7], [1.3, 0.1], size=(20, 2))
    batched = kinematics.com_height_offset(poses)
    for pose, value in zip(poses, batched, strict=True):
        links = kinematics.com_positions(pose)
        expected = sum(robot.LINKS[n].mass * links[n][1] for n in links) / robot.TOTAL_MASS
        assert value == pytest.approx(expected, abs=1e-12)
    # the centre of mass moves with the joints as d/dt of the offset
    q, qd = poses[:1], np.array([[2.0, -3.0]])
    dt = 1e-7
    numeric = (kinematics.com_height_offset(q + dt * qd) - kinematics.com_height_offset(q)) / dt
    assert kinematics.com_vertical_velocity(np.zeros(1), q, qd) == pytest.approx(numeric, rel=1e-4)
