"""Each perturbation of the hopper changes the physics as it says (MuJoCo and PyBullet), the
nominal one changes nothing, and the random ones are a function of the seed."""

from __future__ import annotations

import numpy as np
import pytest

from cpg_actor.robots.common.perturbation import Perturbation
from cpg_actor.robots.hopper import description as robot
from cpg_actor.robots.hopper.backends.mujoco_backend import load_model
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.env import HopperEnv
from cpg_actor.robots.hopper.task import SENSOR_NOISE
from cpg_actor.robots.hopper.vector import HopperVectorEnv

from .helpers import NOMINAL, SIMS


def env(sim="mujoco", num_envs=1, **perturbation) -> HopperVectorEnv:
    config = HopperConfig(sim=sim, perturbation=Perturbation(**perturbation))
    return HopperVectorEnv(num_envs, config=config, num_threads=1)


def actions(steps: int, num_envs: int = 1, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return NOMINAL + rng.uniform(-0.3, 0.3, (steps, num_envs, 2))


def rollout(e: HopperVectorEnv, commands: np.ndarray, seed: int = 3):
    """Observations, and the simulator state after each step."""
    obs, _ = e.reset(seed=seed)
    observed, states = [obs.copy()], []
    for command in commands:
        obs, *_ = e.step(command)
        observed.append(obs.copy())
        states.append(np.concatenate([e.sim.backend.qpos, e.sim.backend.qvel], axis=1))
    return np.array(observed), np.array(states)


def vertical_momentum(e: HopperVectorEnv) -> float:
    """The robot's vertical momentum (kg m/s): every link's mass times its COM's velocity."""
    backend = e.sim.backend
    if e.config.sim == "mujoco":
        import mujoco

        data = backend._load(0)
        mujoco.mj_subtreeVel(backend.model, data)
        return float(data.subtree_linvel[backend._hip, 2] * backend.model.body_subtreemass[1])
    client, body = backend.handle(0)
    total = 0.0
    for link in range(client.getNumJoints(body)):
        mass = client.getDynamicsInfo(body, link)[0]
        state = client.getLinkState(body, link, computeLinkVelocity=1)
        total += mass * state[6][2]
    return total


def test_the_nominal_perturbation_changes_nothing():
    config = HopperConfig()
    assert config.perturbation == Perturbation() and config.perturbation.nominal
    e = env()
    assert e.sim.delay is None and not e.sim.draws.active
    # the model is the shipped one, the actuators and friction of the config's
    shipped = load_model(config.physics_dt, config.foot_friction)
    for name in ("body_mass", "body_inertia", "pair_friction", "actuator_gainprm",
                 "actuator_biasprm", "actuator_dynprm"):  # fmt: skip
        np.testing.assert_array_equal(getattr(e.sim.backend.model, name), getattr(shipped, name))
    # a perturbation given as the nominal values, through a config mapping, is the same env
    commands = actions(60)
    given = HopperVectorEnv(1, config={"perturbation": {"payload": 0, "latency": 0}},
                            num_threads=1)  # fmt: skip
    for a, b in zip(rollout(e, commands), rollout(given, commands), strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("sim", SIMS)
def test_a_payload_adds_its_mass_to_the_robot(sim):
    nominal, loaded = env(sim), env(sim, payload=1.25)
    added = loaded.sim.backend.total_mass() - nominal.sim.backend.total_mass()
    assert added == pytest.approx(1.25, abs=1e-9)
    assert nominal.sim.backend.total_mass() == pytest.approx(robot.TOTAL_MASS, abs=1e-6)
    if sim == "mujoco":  # the derived constants follow: the tree's mass
        model = loaded.sim.backend.model
        assert model.body_subtreemass[0] == pytest.approx(robot.TOTAL_MASS + 1.25)
    # and the physics: the same commands move the loaded robot otherwise
    commands = actions(80)
    assert not np.allclose(rollout(nominal, commands)[1], rollout(loaded, commands)[1])


@pytest.mark.parametrize("sim", SIMS)
def test_latency_applies_each_command_the_given_steps_late(sim):
    """With k steps of latency, commands a_0, a_1, ... move the robot as commands nominal
    (k times), a_0, a_1, ... do without: the drives track the start command until a_0
    arrives."""
    commands = actions(40)
    for k in (1, 3):
        late = rollout(env(sim, latency=float(k)), commands)[1]
        shifted = np.concatenate([np.tile(NOMINAL, (k, 1, 1)), commands[:-k]])
        on_time = rollout(env(sim), shifted)[1]
        np.testing.assert_array_equal(late, on_time)


def test_a_sub_step_latency_applies_the_command_the_given_substeps_late():
    """Half a control step late: for the first 5 of the 10 substeps the drives track the
    last step's command, then this step's."""
    commands = actions(20)
    late = env(latency=0.5)
    late.reset(seed=3)
    direct = env()
    direct.reset(seed=3)
    previous = NOMINAL[None]
    for command in commands:
        late.step(command)
        schedule = np.concatenate([np.repeat(previous[:, None], 5, 1),
                                   np.repeat(command[:, None], 5, 1)], axis=1)  # fmt: skip
        direct.sim.backend.track(schedule, 10)
        previous = command
        np.testing.assert_array_equal(late.sim.backend.qpos, direct.sim.backend.qpos)
        np.testing.assert_array_equal(late.sim.backend.qvel, direct.sim.backend.qvel)


@pytest.mark.parametrize("sim", SIMS)
@pytest.mark.parametrize("direction", ["up", "down"])
def test_a_push_changes_the_momentum_by_its_impulse(sim, direction):
    """In the air (no contact), a push over one control step changes the robot's vertical
    momentum by the impulse given, over what gravity alone does."""
    impulse = 2.0
    gained = []
    for push in (0.0, impulse):
        config = HopperConfig(sim=sim, reset_clearance=0.3, perturbation=Perturbation(
            push=push, push_direction=direction, push_time=(0.0, 0.0)))  # fmt: skip
        e = HopperVectorEnv(1, config=config, num_threads=1)
        e.reset(seed=0)
        before = vertical_momentum(e)
        e.step(NOMINAL[None])
        assert e.sim.foot_height()[0] > 0.0  # still in the air
        gained.append(vertical_momentum(e) - before)
    sign = 1.0 if direction == "up" else -1.0
    assert gained[1] - gained[0] == pytest.approx(sign * impulse, rel=1e-3)


def test_the_push_comes_once_at_a_step_drawn_from_the_seed():
    e = env(push=3.0, push_time=(1.0, 2.0), num_envs=3)
    e.reset(seed=11)
    steps = e.sim.draws.push_step.copy()
    assert np.all((steps >= 100) & (steps <= 200))
    e.reset(seed=11)
    np.testing.assert_array_equal(e.sim.draws.push_step, steps)
    e.reset(seed=12)
    assert not np.array_equal(e.sim.draws.push_step, steps)
    # the env's own draws (the start pose) are the nominal env's
    nominal = env(num_envs=3)
    np.testing.assert_array_equal(nominal.reset(seed=11)[0], e.reset(seed=11)[0])


@pytest.mark.parametrize("sim", SIMS)
def test_friction_reaches_the_contact(sim):
    e = env(sim, friction=0.3)
    e.reset(seed=0)
    for _ in range(20):  # standing: the foot on the ground
        e.step(NOMINAL[None])
    assert e.sim.backend.contact()[0]
    backend = e.sim.backend
    if sim == "mujoco":
        data = backend._load(0)
        assert data.ncon == 1
        np.testing.assert_allclose(data.contact[0].friction[:2], 0.3)
    else:  # Bullet multiplies the two frictions; the ground's is 1
        client, body = backend.handle(0)
        assert client.getDynamicsInfo(body, 3)[1] == pytest.approx(0.3)
        ground = backend._worlds[0].ground
        assert client.getDynamicsInfo(ground, -1)[1] == pytest.approx(1.0)


def test_observation_noise_has_the_given_std():
    """Under the same (open-loop) commands the physics is the nominal env's, and the
    observations differ by the noise: std obs_noise x SENSOR_NOISE per entry, none where the
    robot has no sensor noise."""
    commands = actions(400, num_envs=4)
    clean, states = rollout(env(num_envs=4), commands)
    noisy, noisy_states = rollout(env(num_envs=4, obs_noise=2.0), commands)
    np.testing.assert_array_equal(states, noisy_states)
    noise = (noisy - clean).reshape(-1, clean.shape[-1])
    expected = 2.0 * np.asarray(SENSOR_NOISE)
    np.testing.assert_allclose(noise.std(axis=0), expected, rtol=0.06)
    np.testing.assert_allclose(noise.mean(axis=0), 0.0, atol=0.1 * expected.max())


@pytest.mark.parametrize("sim", SIMS)
def test_motor_strength_scales_the_torque_limit(sim):
    """A joint asked far from where it is gives its torque limit (decimation 1: at rest)."""
    for strength in (1.0, 0.6):
        config = HopperConfig(sim=sim, decimation=1, reset_clearance=0.3,
                              perturbation=Perturbation(motor_strength=strength))  # fmt: skip
        e = HopperVectorEnv(1, config=config, num_threads=1)
        e.reset(seed=0)
        far = np.array([[robot.JOINT_LIMITS["HFE"][1], robot.JOINT_LIMITS["KFE"][0]]])
        *_, info = e.step(far)
        np.testing.assert_allclose(np.abs(info["joint_torque"][0]), 40.0 * strength)


def test_the_single_env_and_the_vector_env_draw_alike():
    """Env 0 of the vector env and a single env with the same seed: the same noise, push and
    trajectory, over an episode end."""
    perturbation = Perturbation(obs_noise=1.0, push=2.0, push_time=(0.05, 0.1), latency=1.0)
    config = HopperConfig(episode_steps=30, perturbation=perturbation)
    vector = HopperVectorEnv(2, config=config, num_threads=1)
    single = HopperEnv(config=config)
    obs, _ = vector.reset(seed=4)
    one, _ = single.reset(seed=4)
    np.testing.assert_array_equal(obs[0], one)
    for command in actions(70, num_envs=2):
        obs, *_, truncated, _ = vector.step(command)
        one, _, _, ended, _ = single.step(command[0])
        if ended:
            one, _ = single.reset()
        np.testing.assert_array_equal(obs[0], one)


def test_resume_is_exact_under_a_perturbation():
    perturbation = Perturbation(obs_noise=1.0, push=2.0, push_time=(0.1, 0.3), latency=1.5)
    config = HopperConfig(episode_steps=40, perturbation=perturbation)
    commands = actions(100, num_envs=2)
    first = HopperVectorEnv(2, config=config, num_threads=1)
    first.reset(seed=1)
    for command in commands[:25]:
        first.step(command)
    state = first.get_state()
    rest = [first.step(command)[0] for command in commands[25:]]
    second = HopperVectorEnv(2, config=config, num_threads=1)
    second.reset(seed=99)
    second.set_state(state)
    again = [second.step(command)[0] for command in commands[25:]]
    np.testing.assert_array_equal(np.array(rest), np.array(again))


def test_mjx_takes_no_perturbation():
    with pytest.raises(ValueError, match="sim='mjx' takes none"):
        HopperConfig(sim="mjx", perturbation=Perturbation(payload=1.0))
    with pytest.raises(ValueError, match="push_direction"):
        HopperConfig(perturbation=Perturbation(push=1.0, push_direction="forward"))
    with pytest.raises(ValueError, match="latency"):
        HopperConfig(perturbation=Perturbation(latency=0.25))  # 2.5 substeps


def test_the_cho2019_env_passes_the_perturbation_to_its_hopper():
    from cpg_actor.config import TrainConfig
    from cpg_actor.robots.registry import get_robot
    from cpg_actor.training.build import make_env

    config = HopperConfig(perturbation=Perturbation(payload=0.5, latency=1.0))
    wrapped = make_env(TrainConfig(agent="cho2019-warm"), get_robot("hopper"), 1, 1, config)
    inner = wrapped.env
    assert inner.sim.backend.total_mass() == pytest.approx(robot.TOTAL_MASS + 0.5)
    assert inner.sim.delay is not None and list(inner.sim.delay.steps) == [1]
    wrapped.close()


RANDOMIZE = {"payload": (0.0, 1.0), "friction": (0.4, 1.2), "latency": (0.0, 2.0),
             "obs_noise": (0.0, 1.0), "motor_strength": (0.8, 1.2)}  # fmt: skip


@pytest.mark.parametrize("sim", SIMS)
def test_randomised_training_draws_each_episode_within_its_ranges(sim):
    config = HopperConfig(sim=sim, episode_steps=5, randomize=RANDOMIZE)
    e = HopperVectorEnv(3, config=config, num_threads=1)
    e.reset(seed=2)
    draws = []
    for _ in range(3):  # three episodes of each env
        draws.append(list(e.sim.draws.episodes))
        for _ in range(5):
            e.step(np.tile(NOMINAL, (3, 1)))
    episodes = [p for row in draws for p in row]
    assert len({p.payload for p in episodes}) == 9  # each episode its own
    for p in episodes:
        for name, (low, high) in RANDOMIZE.items():
            assert low <= getattr(p, name) <= high
        assert (p.latency * 10) % 1 == 0  # whole substeps
    # the physics of each robot is its episode's: its own payload and friction
    backend = e.sim.backend
    for i, p in enumerate(e.sim.draws.episodes):
        if sim == "mujoco":
            model = backend.stepper.model_of(i)
            assert model.body_mass[backend._hip] == pytest.approx(1.42462 + p.payload)
            assert model.pair_friction[0, 0] == pytest.approx(p.friction)
        else:
            client, body = backend.handle(i)
            assert client.getDynamicsInfo(body, 0)[0] == pytest.approx(1.42462 + p.payload)
            assert client.getDynamicsInfo(body, 3)[1] == pytest.approx(p.friction)
        assert e.sim.delay.latency[i] == round(p.latency * 10)
    # reproducible from the seed, and the nominal env's start poses
    again = HopperVectorEnv(3, config=config, num_threads=1)
    again.reset(seed=2)
    nominal = HopperVectorEnv(3, config=HopperConfig(sim=sim), num_threads=1)
    # the unsensed entries (command, hip height and speed): the nominal env's start poses
    np.testing.assert_array_equal(nominal.reset(seed=2)[0][:, 4:], e.reset(seed=2)[0][:, 4:])
    assert again.sim.draws.episodes == e.sim.draws.episodes
    assert again.reset(seed=3) and again.sim.draws.episodes != e.sim.draws.episodes


def test_randomised_training_resumes_exactly():
    config = HopperConfig(episode_steps=15, randomize=RANDOMIZE)
    commands = actions(60, num_envs=2)
    first = HopperVectorEnv(2, config=config, num_threads=1)
    first.reset(seed=1)
    for command in commands[:20]:
        first.step(command)
    state = first.get_state()
    rest = [first.step(command)[0] for command in commands[20:]]  # episodes end, new draws
    second = HopperVectorEnv(2, config=config, num_threads=1)
    second.reset(seed=7)
    second.set_state(state)
    again = [second.step(command)[0] for command in commands[20:]]
    np.testing.assert_array_equal(np.array(rest), np.array(again))
    assert first.sim.draws.episodes == second.sim.draws.episodes


def test_randomisation_and_a_fixed_perturbation_of_the_same_field_are_refused():
    with pytest.raises(ValueError, match="perturbation.payload and randomize"):
        HopperConfig(perturbation=Perturbation(payload=1.0), randomize={"payload": (0.0, 1.0)})
    with pytest.raises(ValueError, match="randomize.friction"):
        HopperConfig(randomize={"friction": (1.0, 0.5)})
    HopperConfig(perturbation=Perturbation(push=1.0), randomize={"payload": (0.0, 1.0)})
