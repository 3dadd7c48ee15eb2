"""``env.command_filter``: a first-order low-pass on the hopper's desired positions (the
comparison at matched smoothness). The pure function's step response; the env's desired
positions follow it from the reset's pose, restart at every reset, are smoother for the same
rough commands, and are what the evaluation's smoothness metric reads; 1.0 changes nothing,
bit for bit; bad values are one clear error."""

from types import SimpleNamespace

import numpy as np
import pytest

from cpg_actor.metrics import signals
from cpg_actor.robots.hopper import task
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.env import HopperEnv
from cpg_actor.robots.hopper.vector import HopperVectorEnv
from cpg_actor.training.evaluation import evaluate
from training.test_eval_traces import ScriptedPolicy  # tests/training  # noqa: I001

NOMINAL = task.NOMINAL_POSE


def rough_commands(steps: int, num_envs: int, seed: int = 0) -> np.ndarray:
    """Commands jumping anywhere in the joint range at every step (bang-bang-like), float32
    as the action space's."""
    rng = np.random.default_rng(seed)
    return rng.uniform(task.ACTION_LOW, task.ACTION_HIGH, size=(steps, num_envs, 2)).astype(
        np.float32
    )


def drive(commands, num_envs, **overrides):
    """The desired positions, observations and rewards of a vector env stepped with
    ``commands`` after ``reset(seed=3)``."""
    env = HopperVectorEnv(num_envs, num_threads=1, **overrides)
    try:
        env.reset(seed=3)
        desired, obs, reward = [], [], []
        for command in commands:
            o, r, _, _, info = env.step(command)
            desired.append(info["desired_position"].copy())
            obs.append(o.copy())
            reward.append(r.copy())
    finally:
        env.close()
    return np.array(desired), np.array(obs), np.array(reward)


# -- the pure function ----------------------------------------------------------------------
@pytest.mark.parametrize("alpha", [0.2, 0.5, 0.9])
def test_step_response_is_first_order(alpha):
    """From 0 toward a constant 1: 1 - (1 - alpha)^k after k steps."""
    desired, command = np.zeros(2), np.ones(2)
    for k in range(1, 30):
        desired = task.command_filter(desired, command, alpha)
        assert desired == pytest.approx(np.full(2, 1.0 - (1.0 - alpha) ** k), rel=1e-12)


def test_alpha_one_is_the_command_itself():
    command = np.array([0.3, -1.1])
    assert task.command_filter(np.array([0.4, -0.8]), command, 1.0) is command


def test_the_same_function_on_jax_arrays():
    jnp = pytest.importorskip("jax.numpy")
    previous, command = np.array([0.4, -0.8]), np.array([1.0, -0.2])
    out = task.command_filter(jnp.asarray(previous, jnp.float32), jnp.asarray(command), 0.25)
    assert out.dtype == jnp.float32
    np.testing.assert_allclose(np.asarray(out), previous + 0.25 * (command - previous), rtol=1e-6)


# -- the env --------------------------------------------------------------------------------
def test_alpha_one_matches_the_unfiltered_env_bit_for_bit():
    commands = rough_commands(40, 3)
    plain = drive(commands, 3)
    off = drive(commands, 3, command_filter=1.0)
    for a, b in zip(plain, off, strict=True):
        np.testing.assert_array_equal(a, b)


def test_the_filtered_env_tracks_the_recurrence_from_the_reset_pose():
    alpha = 0.3
    commands = rough_commands(30, 2)
    desired, obs, _ = drive(commands, 2, command_filter=alpha)
    expected, previous = [], np.tile(NOMINAL, (2, 1))
    for command in commands:
        previous = previous + alpha * (command - previous)
        expected.append(previous)
    np.testing.assert_allclose(desired, np.array(expected), rtol=1e-12)
    # the observation's desired positions are the filter's state: the task stays Markov
    np.testing.assert_allclose(obs[:, :, 4:6], desired, rtol=1e-6)


def test_a_filtered_command_is_smoother_for_the_same_rough_commands():
    commands = rough_commands(60, 2)
    rough = drive(commands, 2)[0]
    smooth = drive(commands, 2, command_filter=0.2)[0]
    # the power gain of a first-order low-pass at the highest frequency: (a / (2 - a))^2
    assert signals.smoothness(smooth[:, 0]) < 0.1 * signals.smoothness(rough[:, 0])


def test_every_reset_restarts_the_filter():
    alpha, steps = 0.5, 10
    commands = rough_commands(steps + 2, 1)
    desired, obs, _ = drive(commands, 1, command_filter=alpha, episode_steps=steps)
    # the autoreset after the truncated episode: its first observation holds the nominal pose,
    # and the next step starts from it, not from the last episode's desired positions
    np.testing.assert_allclose(obs[steps - 1, 0, 4:6], NOMINAL, rtol=1e-6)
    first = NOMINAL + alpha * (commands[steps, 0] - NOMINAL)
    np.testing.assert_allclose(desired[steps, 0], first, rtol=1e-12)
    # the single env, reset by hand in the middle of an episode
    env = HopperEnv(command_filter=alpha)
    try:
        env.reset(seed=0)
        for command in commands[:5, 0]:
            env.step(command)
        _, info = env.reset(seed=0)
        np.testing.assert_array_equal(info["desired_position"], NOMINAL)
        *_, info = env.step(commands[5, 0])
        expected = NOMINAL + alpha * (commands[5, 0] - NOMINAL)
        np.testing.assert_allclose(info["desired_position"], expected, rtol=1e-12)
    finally:
        env.close()


def test_the_smoothness_metric_reads_the_filtered_command():
    """The evaluation's traces (the command smoothness of the reports) hold the desired
    positions the motors got, not the agent's rough command."""
    script = rough_commands(30, 1)[:, 0]
    found = {}
    for alpha in (1.0, 0.2):
        env = HopperVectorEnv(1, config=HopperConfig(episode_steps=30, command_filter=alpha),
                              num_threads=1)  # fmt: skip
        try:
            traces = evaluate(ScriptedPolicy(script), env, seed=0, control_dt=0.01, max_steps=30)
        finally:
            env.close()
        found[alpha] = traces["desired_position"][:, 0]
    expected, previous = [], NOMINAL
    for command in script:
        previous = previous + 0.2 * (command - previous)
        expected.append(previous)
    np.testing.assert_allclose(found[0.2], np.array(expected), rtol=1e-12)
    assert signals.smoothness(found[0.2]) < 0.1 * signals.smoothness(found[1.0])


@pytest.mark.parametrize("bad", [0, 0.0, -0.5, 1.01, float("nan"), "0.5", True, None])
def test_bad_values_are_one_clear_error(bad):
    accepted = r"command_filter must be a number in \(0, 1\]"
    with pytest.raises(ValueError, match=accepted):
        HopperConfig(command_filter=bad)
    with pytest.raises(ValueError, match=accepted):
        HopperEnv(command_filter=bad)  # before any simulator is created


def test_a_run_config_takes_it_from_the_command_line():
    from cpg_actor.config.train_config import compose_config

    config = compose_config(values={"agent": "mlp-warm"}, overrides=["env.command_filter=0.35"])
    assert config.env.command_filter == 0.35
    assert compose_config(values={"agent": "mlp-warm"}).env.command_filter == 1.0
    with pytest.raises(ValueError, match="command_filter must be a number in"):
        compose_config(overrides=["env.command_filter=2"])


def test_export_refuses_a_run_trained_with_the_filter(tmp_path):
    """The exported control step holds no filter: a deployment would send the rough command."""
    from cpg_actor.deploy.export import export_policy

    run = SimpleNamespace(agent="mlp-warm", env=HopperConfig(command_filter=0.5))
    with pytest.raises(ValueError, match="env.command_filter=0.5"):
        export_policy(SimpleNamespace(config=run), tmp_path / "policy.onnx", "onnx")
    assert not any(tmp_path.iterdir())
