"""The perturbations on the quadrupeds (ANYmal B's MuJoCo env, the shared code), the robots'
perturbation tables, and the perturbation as a config section."""

from __future__ import annotations

import numpy as np
import pytest

from cpg_actor.config import TrainConfig, compose_config
from cpg_actor.robots.anymal.vector import ANYMAL, AnymalVectorEnv
from cpg_actor.robots.common.mujoco_runtime import STATE_SPEC, mujoco
from cpg_actor.robots.common.perturbation import CommandDelay, Perturbation
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.common.quadruped.vector import load_model
from cpg_actor.robots.registry import ROBOTS
from cpg_actor.tasks import velocity as task

NOMINAL = np.array(ANYMAL.nominal_pose)


def anymal(num_envs=1, config=None, **perturbation) -> AnymalVectorEnv:
    config = config or QuadrupedConfig(perturbation=Perturbation(**perturbation))
    return AnymalVectorEnv(num_envs, config.validate(), num_threads=1)


def actions(steps, num_envs=1, seed=0):
    rng = np.random.default_rng(seed)
    return NOMINAL + rng.uniform(-0.1, 0.1, (steps, num_envs, 12))


def rollout(env, commands, seed=3):
    obs, _ = env.reset(seed=seed)
    observed, states = [obs.copy()], []
    for command in commands:
        obs, *_ = env.step(command)
        observed.append(obs.copy())
        states.append(env.qpos.copy())
    return np.array(observed), np.array(states)


def momentum(env, index=0) -> np.ndarray:
    """The robot's linear momentum (kg m/s, world frame)."""
    data = mujoco.MjData(env.model)
    mujoco.mj_setState(env.model, data, env._state[index], STATE_SPEC)
    mujoco.mj_forward(env.model, data)
    mujoco.mj_subtreeVel(env.model, data)
    base = env.model.body(ANYMAL.base_body).id
    return data.subtree_linvel[base] * env.model.body_subtreemass[base]


def lift(env, height=1.0) -> None:
    """Every robot ``height`` higher (in the air), as it was otherwise."""
    env.qpos[:, 2] += height
    env._refresh_sensors(np.arange(env.num_envs))


def test_the_nominal_perturbation_changes_nothing():
    env = anymal()
    assert env.delay is None and not env.draws.active
    given = anymal(config=QuadrupedConfig.from_dict({"perturbation": {"friction": None}}))
    commands = actions(50)
    for a, b in zip(rollout(env, commands), rollout(given, commands), strict=True):
        np.testing.assert_array_equal(a, b)


def test_a_payload_adds_its_mass_to_the_base():
    config = QuadrupedConfig()
    nominal = load_model(ANYMAL, config)
    loaded = load_model(ANYMAL, config.replace(perturbation=Perturbation(payload=6.0)))
    added = mujoco.mj_getTotalmass(loaded) - mujoco.mj_getTotalmass(nominal)
    assert added == pytest.approx(6.0, abs=1e-9)
    base = loaded.body(ANYMAL.base_body).id
    assert loaded.body_mass[base] - nominal.body_mass[base] == pytest.approx(6.0)
    assert loaded.body_subtreemass[base] == pytest.approx(ANYMAL.total_mass + 6.0, abs=1e-4)


def test_latency_applies_each_command_the_given_steps_late():
    """The drives hold the episode's start pose until the first command arrives, k steps
    late: as the nominal env under the start pose k times, then the commands."""
    commands = actions(30)
    late = rollout(anymal(latency=2.0), commands)[1]
    env = anymal()
    env.reset(seed=3)
    start = env.episode.last_action.copy()  # the start pose (nominal plus reset noise)
    shifted = np.concatenate([np.repeat(start[None], 2, 0), commands[:-2]])
    np.testing.assert_array_equal(late, rollout(env, shifted)[1])


@pytest.mark.parametrize("direction, axis", [("forward", 0), ("backward", 0), ("left", 1)])
def test_a_push_changes_the_momentum_by_its_impulse(direction, axis):
    """In the air, a horizontal push over one control step changes the robot's momentum by
    the impulse, in the direction of the base's heading frame."""
    impulse = 15.0
    gained = []
    for push in (0.0, impulse):
        env = anymal(push=push, push_direction=direction, push_time=(0.0, 0.0))
        env.reset(seed=0)
        lift(env)
        before = momentum(env)
        env.step(NOMINAL[None])
        gained.append(momentum(env) - before)
    change = gained[1] - gained[0]
    sign = -1.0 if direction == "backward" else 1.0
    expected = np.zeros(3)
    expected[axis] = sign * impulse
    # the integrator's error: the pushed robot's legs swing otherwise, and the momentum is read
    # from the configuration after the step
    np.testing.assert_allclose(change, expected, atol=5e-3 * impulse)


def test_friction_reaches_the_contact():
    env = anymal(friction=0.35)
    env.reset(seed=0)
    for _ in range(10):
        env.step(NOMINAL[None])
    data = mujoco.MjData(env.model)
    mujoco.mj_setState(env.model, data, env._state[0], STATE_SPEC)
    mujoco.mj_forward(env.model, data)
    feet = {env.model.geom(f"{leg}_foot").id for leg in ANYMAL.legs}
    contacts = [c for c in data.contact[: data.ncon] if {c.geom1, c.geom2} & feet]
    assert len(contacts) >= 2
    for contact in contacts:
        assert contact.friction[0] == pytest.approx(0.35)


def test_observation_noise_has_the_given_std():
    commands = actions(200, num_envs=4)
    clean, states = rollout(anymal(4), commands)
    noisy, noisy_states = rollout(anymal(4, obs_noise=1.5), commands)
    np.testing.assert_array_equal(states, noisy_states)
    noise = (noisy - clean).reshape(-1, clean.shape[-1])
    expected = 1.5 * task.sensor_noise(12)
    sensed = expected > 0
    np.testing.assert_allclose(noise.std(axis=0)[sensed], expected[sensed], rtol=0.08)
    assert np.all(noise[:, ~sensed] == 0.0)  # the command and the last action: none


def test_motor_strength_scales_the_drives():
    """The model under motor strength s is the model of gains, torque limit and stall torque
    scaled by s."""
    config = QuadrupedConfig()
    scaled = load_model(ANYMAL, config.replace(perturbation=Perturbation(motor_strength=0.7)))
    by_hand = load_model(ANYMAL, config.replace(
        kp=0.7 * config.kp, kd=0.7 * config.kd, torque_limit=0.7 * config.torque_limit,
        saturation_torque=0.7 * config.saturation_torque))  # fmt: skip
    for name in ("actuator_gainprm", "actuator_biasprm", "actuator_dynprm", "actuator_forcerange"):
        np.testing.assert_allclose(getattr(scaled, name), getattr(by_hand, name))
    assert not np.allclose(scaled.actuator_gainprm, load_model(ANYMAL, config).actuator_gainprm)


def test_resume_is_exact_under_a_perturbation():
    perturbation = Perturbation(obs_noise=1.0, push=10.0, push_time=(0.1, 0.3), latency=1.5,
                                push_direction="left")  # fmt: skip
    config = QuadrupedConfig(episode_seconds=0.6, perturbation=perturbation)
    commands = actions(60, num_envs=2)
    first = anymal(2, config=config)
    first.reset(seed=1)
    for command in commands[:17]:
        first.step(command)
    state = first.get_state()
    rest = [first.step(command)[0] for command in commands[17:]]
    second = anymal(2, config=config)
    second.reset(seed=5)
    second.set_state(state)
    np.testing.assert_array_equal(np.array(rest), [second.step(c)[0] for c in commands[17:]])


def test_mjx_takes_no_perturbation():
    with pytest.raises(ValueError, match="sim='mjx' takes none"):
        QuadrupedConfig(sim="mjx", perturbation=Perturbation(obs_noise=1.0)).validate()


def test_command_delay():
    latency = Perturbation(latency=1.5).substeps(4)
    delay = CommandDelay(latency, decimation=4, num_envs=2, num_joints=1, longest=8)
    delay.set_latency(1, 4)  # robot 1: one step late
    assert latency == 6 and list(delay.steps) == [1, 1]
    delay.reset([0, 1], 0.0)
    schedules = [delay.schedule(np.array([[float(t)], [float(t)]]))[:, :, 0] for t in (1, 2, 3)]
    # robot 0: substeps 0-1 of step t track the command of step t - 2, then that of t - 1
    np.testing.assert_array_equal([s[0] for s in schedules],
                                  [[0, 0, 0, 0], [0, 0, 1, 1], [1, 1, 2, 2]])  # fmt: skip
    np.testing.assert_array_equal([s[1] for s in schedules],
                                  [[0, 0, 0, 0], [1, 1, 1, 1], [2, 2, 2, 2]])  # fmt: skip


def test_every_robot_declares_its_perturbations_sized_to_its_mass():
    for name, robot in ROBOTS.items():
        table = robot.perturbations
        assert table is not None, name
        mass = mujoco.MjModel.from_xml_string(robot.mjcf(robot.config_class())).body_mass.sum()
        if hasattr(robot.config_class, "moving_mass"):
            assert robot.config_class.moving_mass == pytest.approx(mass, rel=1e-6)
        payload = table.axes["payload"].levels
        assert payload[0] == pytest.approx(0.1 * mass, abs=0.01)
        assert payload[-1] == pytest.approx(0.5 * mass, abs=0.01)
        for axis in table.axes.values():  # 3-5 increasing levels, the robot accepts each
            assert 3 <= len(axis.levels) <= 5 and list(axis.levels) == sorted(axis.levels)
            for level in axis.levels:
                robot.config_class().replace(perturbation=axis.perturbation(level))
        assert set(table.metrics) <= set(robot.metrics)


def test_the_perturbation_is_a_config_section():
    config = compose_config(overrides=["env.perturbation.payload=0.5",
                                       "env.perturbation.push_time=[0.5, 1]",
                                       "env.perturbation.friction=0.3"])  # fmt: skip
    assert config.env.perturbation == Perturbation(payload=0.5, friction=0.3,
                                                   push_time=(0.5, 1.0))  # fmt: skip
    again = TrainConfig.from_dict(config.to_dict())
    assert again.env.perturbation == config.env.perturbation
    with pytest.raises(ValueError, match="unknown perturbation key"):
        compose_config(overrides=["env.perturbation.mass=1"])
    with pytest.raises(ValueError, match="payload"):
        compose_config(overrides=["env.perturbation.payload=-1"])
    quadruped = compose_config(overrides=["robot=anymal", "env.perturbation.latency=2"])
    assert quadruped.env.perturbation.latency == 2.0


def test_randomised_training_gives_each_env_its_episode_physics():
    randomize = {"payload": (1.0, 6.0), "friction": (0.4, 1.2), "motor_strength": (0.8, 1.2),
                 "latency": (0.0, 1.0)}  # fmt: skip
    env = anymal(3, config=QuadrupedConfig(randomize=randomize))
    env.reset(seed=4)
    base = env.model.body(ANYMAL.base_body).id
    nominal = load_model(ANYMAL, QuadrupedConfig())
    for i, episode in enumerate(env.draws.episodes):
        model = env.stepper.model_of(i)
        assert model.body_mass[base] == pytest.approx(nominal.body_mass[base] + episode.payload)
        assert model.geom_friction[model.geom("ground").id, 0] == pytest.approx(episode.friction)
        limits = episode.motor_strength * nominal.actuator_forcerange
        np.testing.assert_allclose(model.actuator_forcerange, limits)
        assert env.delay.latency[i] == round(episode.latency * 10)
    assert len({p.payload for p in env.draws.episodes}) == 3


def test_the_single_robot_env_draws_as_env_0_of_the_vector_env():
    from cpg_actor.robots.anymal.env import AnymalEnv

    config = QuadrupedConfig(episode_seconds=0.3, perturbation=Perturbation(
        obs_noise=1.0, push=10.0, push_time=(0.1, 0.2), push_direction="left"))  # fmt: skip
    vector, single = anymal(2, config=config), AnymalEnv(config=config)
    obs, _ = vector.reset(seed=6)
    np.testing.assert_array_equal(single.reset(seed=6)[0], obs[0])
    for command in actions(40, num_envs=2):
        obs, *_ = vector.step(command)
        one, _, terminated, truncated, _ = single.step(command[0])
        if terminated or truncated:
            one, _ = single.reset()
        np.testing.assert_array_equal(one, obs[0])
