"""Randomised training's terms for the quadrupeds (``env.randomize``): PD gains, passive joint
damping, armature, contact softness and pushes during the episode, with each robot's field
ranges (``randomize.preset=field``); off, the envs compute what they computed before; the
hopper refuses the terms it does not take, in one line."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cpg_actor.config import compose_config
from cpg_actor.robots.common.perturbation import Perturbation, Randomization
from cpg_actor.robots.common.perturbation.values import MODEL_TERMS, RANDOMIZED
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.common.quadruped.vector import load_model
from cpg_actor.robots.go1.config import Go1Config
from cpg_actor.robots.go1.vector import Go1VectorEnv
from cpg_actor.robots.hopper.config import HopperConfig

NOMINAL = np.array((0.0, 0.9, -1.8) * 4)


def go1(num_envs: int, **randomize) -> Go1VectorEnv:
    config = Go1Config(episode_seconds=1.0, randomize=Randomization(**randomize))
    return Go1VectorEnv(num_envs, config.validate(), num_threads=1)


def run(env, steps: int, seed: int = 5) -> tuple[np.ndarray, np.ndarray]:
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(0)
    observed, rewards = [obs.copy()], []
    for _ in range(steps):
        action = NOMINAL + rng.uniform(-0.1, 0.1, (env.num_envs, 12))
        obs, reward, *_ = env.step(action)
        observed.append(obs.copy())
        rewards.append(reward.copy())
    return np.array(observed), np.array(rewards)


def test_the_draws_stay_in_the_robots_field_ranges():
    for config_class in (Go1Config, QuadrupedConfig):
        config = config_class(randomize={"preset": "field"}).validate()
        randomize = config.randomize
        for name, bounds in config_class.FIELD_RANDOMIZATION.items():
            assert getattr(randomize, name) == tuple(bounds), name
        rng = np.random.default_rng(1)
        for _ in range(200):
            episode = randomize.draw(rng, config.decimation, Perturbation())
            for name in RANDOMIZED:
                low, high = getattr(randomize, name) or (None, None)
                if low is not None:
                    assert low - 1e-12 <= getattr(episode, name) <= high + 1e-12, name


def test_a_given_range_wins_over_the_preset():
    config = Go1Config(randomize={"preset": "field", "kp_scale": (0.9, 0.95)}).validate()
    assert config.randomize.kp_scale == (0.9, 0.95)
    assert config.randomize.kd_scale == Go1Config.FIELD_RANDOMIZATION["kd_scale"]


def test_each_model_term_reaches_each_envs_model():
    ranges = {"kp_scale": (0.8, 1.3), "kd_scale": (0.5, 1.5), "joint_damping": (0.0, 1.5),
              "armature": (1.0, 1.05), "contact_softness": (0.5, 2.0)}  # fmt: skip
    env = go1(3, **ranges)
    env.reset(seed=2)
    quadruped = env.quadruped
    nominal = load_model(quadruped, Go1Config())
    ground = nominal.geom("ground").id
    for i, episode in enumerate(env.draws.episodes):
        model = env.stepper.model_of(i)
        np.testing.assert_allclose(
            model.actuator_gainprm[:, 4], episode.kp_scale * nominal.actuator_gainprm[:, 4]
        )
        np.testing.assert_allclose(
            model.actuator_gainprm[:, 6], episode.kd_scale * nominal.actuator_gainprm[:, 6]
        )
        np.testing.assert_allclose(
            model.dof_damping[6:], episode.joint_damping * nominal.dof_damping[6:]
        )
        np.testing.assert_allclose(
            model.dof_armature[6:], episode.armature * nominal.dof_armature[6:]
        )
        np.testing.assert_array_equal(model.dof_damping[:6], nominal.dof_damping[:6])
        assert model.geom_solref[ground, 0] == pytest.approx(
            episode.contact_softness * nominal.geom_solref[ground, 0]
        )
        foot = model.geom(f"{quadruped.legs[0]}_foot").id
        assert model.geom_solref[foot, 0] == pytest.approx(
            episode.contact_softness * nominal.geom_solref[foot, 0])  # fmt: skip
    for name in ranges:  # each env drew its own
        assert len({getattr(p, name) for p in env.draws.episodes}) == 3, name


@pytest.mark.parametrize("term", MODEL_TERMS)
def test_each_model_term_changes_the_motion(term):
    base = run(go1(1), 20)[0]
    value = 0.0 if term == "joint_damping" else 2.0
    changed = run(go1(1, **{term: (value, value)}), 20)[0]
    assert not np.allclose(base[-1], changed[-1])


def test_training_pushes_kick_the_base_every_few_seconds():
    env = go1(2, push_velocity=(0.5, 1.0), push_interval=(0.2, 0.3))
    env.reset(seed=3)
    recorded, kicks = [], env.draws.kicks

    def spy(elapsed):  # what each step applies
        kick = kicks(elapsed)
        if kick is not None:
            recorded.append((elapsed.copy(), kick.copy()))
        return kick

    env.draws.kicks = spy
    for _ in range(40):  # 0.8 s of 1 s episodes: pushes every 0.2-0.3 s (10-15 steps)
        env.step(np.tile(NOMINAL, (2, 1)))
    sizes = [np.linalg.norm(k[i]) for _, k in recorded for i in range(2) if k[i].any()]
    assert len(sizes) >= 4 and all(0.5 <= size <= 1.0 for size in sizes)
    steps = [int(e[0]) for e, k in recorded if k[0].any()]
    assert steps and 10 <= steps[0] <= 15
    assert all(10 <= b - a <= 15 for a, b in zip(steps, steps[1:], strict=False))


def test_a_push_changes_the_base_velocity_by_its_kick():
    env = go1(1, push_velocity=(0.8, 0.8), push_interval=(0.1, 0.1))
    env.reset(seed=0)
    for _ in range(5):
        env.step(NOMINAL[None])
    quiet = go1(1)
    quiet.reset(seed=0)
    for _ in range(5):
        quiet.step(NOMINAL[None])
    np.testing.assert_array_equal(env.qvel, quiet.qvel)  # no push yet
    # one kick of 0.8 m/s after 5 steps (0.1 s): the horizontal speeds part by about that much
    env.step(NOMINAL[None])
    quiet.step(NOMINAL[None])
    gap = np.linalg.norm(env.qvel[0, :2] - quiet.qvel[0, :2])
    assert 0.3 < gap < 1.0


def test_off_is_bit_identical_and_the_old_terms_draw_as_before():
    base_obs, base_rewards = run(go1(2), 15)
    # all defaults written out: the same env as no randomize at all
    explicit = dataclasses.asdict(Randomization())
    obs, rewards = run(go1(2, **explicit), 15)
    np.testing.assert_array_equal(obs, base_obs)
    np.testing.assert_array_equal(rewards, base_rewards)
    # the old terms only: the new ones draw nothing (the same episodes as before)
    old = Randomization(payload=(0.0, 1.0), friction=(0.5, 1.0))
    rng_a, rng_b = np.random.default_rng(9), np.random.default_rng(9)
    a = old.draw(rng_a, 10, Perturbation())
    b = dataclasses.replace(old, kp_scale=(1.0, 1.0)).draw(rng_b, 10, Perturbation())
    assert a == b and rng_a.random() == rng_b.random()


@pytest.mark.parametrize(
    ("randomize", "message"),
    [
        ({"kp_scale": (1.2, 0.8)}, r"randomize.kp_scale must be \[low, high\] with 0 < low"),
        ({"joint_damping": (-0.1, 1.0)}, r"randomize.joint_damping must be \[low, high\]"),
        ({"push_velocity": (0.0, 50.0)}, r"randomize.push_velocity must be .* <= 10"),
        ({"push_interval": (0.0, 5.0)}, r"randomize.push_interval must be .* 0 < low"),
        ({"preset": "legged_gym"}, r"randomize.preset must be one of '', 'field'"),
    ],
)
def test_bad_ranges_are_one_line(randomize, message):
    with pytest.raises(ValueError, match=message) as error:
        Go1Config(randomize=randomize).validate()
    assert len(str(error.value).splitlines()) == 1


def test_the_hopper_refuses_the_quadrupeds_terms_in_one_line():
    with pytest.raises(ValueError, match=r"randomize.joint_damping is not supported on the "
                                         r"hopper; it randomises payload") as error:  # fmt: skip
        HopperConfig(randomize={"joint_damping": (0.5, 1.5)}).validate()
    assert len(str(error.value).splitlines()) == 1
    with pytest.raises(ValueError, match=r"randomize.push_velocity is not supported"):
        HopperConfig(randomize={"push_velocity": (0.0, 1.0)}).validate()
    with pytest.raises(ValueError, match=r"perturbation.armature is not supported on the hopper"):
        HopperConfig(perturbation={"armature": 2.0}).validate()
    hopper = HopperConfig(randomize={"preset": "field"})
    hopper.validate()
    assert hopper.randomize.motor_strength == (0.8, 1.2)


def test_the_forward_preset_trains_without_randomisation():
    config = compose_config(overrides=["robot=go1"])
    assert not config.env.randomize.active
    field = compose_config(overrides=["robot=go1", "env.randomize.preset=field"])
    assert field.env.randomize.kd_scale == (0.5, 1.5) and field.env.randomize.pushes


def test_a_resumed_env_pushes_and_draws_as_the_uninterrupted_one():
    ranges = {"push_velocity": (0.5, 1.0), "push_interval": (0.1, 0.2), "kp_scale": (0.8, 1.2),
              "joint_damping": (0.0, 1.5)}  # fmt: skip
    rng = np.random.default_rng(4)
    commands = NOMINAL + rng.uniform(-0.1, 0.1, (80, 2, 12))
    env = go1(2, **ranges)
    env.reset(seed=8)
    for command in commands[:30]:
        env.step(command)
    state = env.get_state()
    straight = [env.step(command)[0].copy() for command in commands[30:]]
    resumed = go1(2, **ranges)
    resumed.reset(seed=123)
    resumed.set_state(state)
    again = [resumed.step(command)[0].copy() for command in commands[30:]]
    np.testing.assert_array_equal(np.array(again), np.array(straight))
