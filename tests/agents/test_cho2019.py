"""The Cho et al. 2019 agents: warm start toward the reference, end-to-end training."""

import json

import numpy as np
import pytest
import torch

from cpg_actor.agents.warm_start import WarmStartConfig
from cpg_actor.config import TrainConfig
from cpg_actor.ppo import PPOConfig
from cpg_actor.robots.hopper.agents import reference_action
from cpg_actor.robots.hopper.cho2019 import action_to_parameters
from cpg_actor.robots.hopper.cho2019_reference import REFERENCE_PARAMETERS
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.registry import get_robot
from cpg_actor.training.build import make_env
from cpg_actor.training.runner import Runner


def config(agent, iterations=2, **warm):
    return TrainConfig(
        agent=agent,
        seed=1,
        num_envs=4,
        total_steps=iterations * 4 * 16,
        checkpoint_interval=100,
        ppo=PPOConfig(num_steps=16, num_epochs=2, num_minibatches=2),
        warm_start=WarmStartConfig(**{"rollout_steps": 100, "minibatch_size": 128, **warm}),
        env=HopperConfig(episode_steps=100),
    )


def mean_action(runner, obs):
    with torch.no_grad():
        obs_n = runner.policy.normalize(torch.as_tensor(obs), update=False)
        return runner.agent.actor(obs_n, runner.agent.initial_state(len(obs))).mean.numpy()


def test_reference_action_maps_back_to_the_reference_parameters():
    np.testing.assert_allclose(
        action_to_parameters(reference_action()), REFERENCE_PARAMETERS, rtol=1e-6
    )


def test_warm_start_brings_the_actor_mean_to_the_reference(tmp_path):
    runner = Runner(config("cho2019-warm"), tmp_path / "run", tensorboard=False)
    obs, _ = runner.env.unwrapped.reset(seed=123)
    before = np.abs(mean_action(runner, obs) - reference_action()).max()
    losses = runner.run_warm_start()
    assert len(losses) == 100  # the paper's 100 epochs
    assert losses[-1] < 1e-3 * losses[0]
    # on observations of a different episode, driven by the reference itself
    for _ in range(30):
        obs, *_ = runner.env.unwrapped.step(np.tile(reference_action(), (4, 1)))
    after = np.abs(mean_action(runner, obs) - reference_action()).max()
    assert before > 0.3 and after < 0.05, (before, after)
    assert json.loads((tmp_path / "run" / "warm_start.json").read_text())["loss"] == losses
    runner.close()


@pytest.mark.parametrize("agent", ["cho2019", "cho2019-warm"])
def test_cho2019_agents_train_end_to_end(tmp_path, agent):
    runner = Runner(config(agent, epochs=5), tmp_path / agent, tensorboard=False)
    assert runner.env.single_action_space.shape == (5,)
    assert runner.env.single_observation_space.shape == (16,)
    start = {k: v.clone() for k, v in runner.agent.state_dict().items()}
    runner.learn()
    assert runner.iteration == 2
    changed = [k for k, v in runner.agent.state_dict().items() if not torch.equal(v, start[k])]
    assert any(k.startswith("actor_mlp") for k in changed) and "log_std" in changed
    assert (tmp_path / agent / "warm_start.json").exists() == (agent == "cho2019-warm")
    runner.close()


def test_warm_start_runs_only_for_a_new_run(tmp_path, monkeypatch):
    first = Runner(
        config("cho2019-warm", iterations=1, epochs=3), tmp_path / "r", tensorboard=False
    )
    first.learn()
    first.close()
    calls = []
    resumed = Runner(
        config("cho2019-warm", iterations=2, epochs=3), tmp_path / "r", tensorboard=False
    )
    resumed.load_checkpoint(resumed.last_checkpoint_path())
    monkeypatch.setattr(resumed, "run_warm_start", lambda: calls.append(1))
    resumed.learn()
    assert calls == [] and resumed.iteration == 2
    resumed.close()


def test_eval_traces_of_cho2019_hold_the_cpg_signals():
    from cpg_actor.training.evaluation import evaluate_policy

    runner = Runner(config("cho2019"), None, tensorboard=False)
    traces = evaluate_policy(runner.policy, runner.config, 4, seed=5)
    runner.close()
    steps = traces["time"].shape[0]
    assert steps == 100
    for key in ("theta_dot", "r_ddot", "desired_velocity", "desired_position"):
        assert traces[key].shape == (steps, 4, 2), key
    # the untrained actor's mean is 0: the middle of each range, the same for every env
    nu_mid = action_to_parameters(np.zeros(5))[0]
    assert np.all(np.abs(traces["cpg_parameters"][:, :, 0] - nu_mid) < 0.2)
    # desired positions are the CPG output around the nominal pose, not the raw action
    assert np.all(traces["desired_position"][:, :, 1] < 0.1)


def test_a_run_resumed_at_iteration_0_is_not_warm_started_again(tmp_path):
    """Killed before its first PPO checkpoint, a cho2019-warm run resumes from iter_000000.pt
    (the warm-started agent) and equals the uninterrupted run."""
    straight = Runner(config("cho2019-warm", epochs=3), tmp_path / "a", tensorboard=False)
    straight.learn()
    resumed = Runner(config("cho2019-warm", epochs=3), tmp_path / "b", tensorboard=False)
    resumed.load_checkpoint(tmp_path / "a" / "checkpoints" / "iter_000000.pt")
    assert resumed.iteration == 0
    resumed.learn()
    try:
        assert not (tmp_path / "b" / "warm_start.json").exists()
        for key, value in straight.agent.state_dict().items():
            assert torch.equal(value, resumed.agent.state_dict()[key]), key
        assert straight.last_evaluation["eval/return"] == resumed.last_evaluation["eval/return"]
    finally:
        straight.close()
        resumed.close()


def test_cho2019_agents_declare_the_cpg_wrapper_around_the_robot_env():
    from cpg_actor.agents import get_agent_spec
    from cpg_actor.robots.hopper.cho2019 import CPGParameterVectorEnv
    from cpg_actor.robots.hopper.vector import HopperVectorEnv

    env = make_env(TrainConfig(agent="cho2019"), get_robot("hopper"), 2, 1)
    try:
        assert isinstance(env, CPGParameterVectorEnv) and isinstance(env.env, HopperVectorEnv)
        assert env.robot == env.env.robot and env.single_action_space.shape == (5,)
    finally:
        env.close()
    assert get_agent_spec("mlp").wrapper is None
    with pytest.raises(ValueError, match="belong to the wrapped env"):
        CPGParameterVectorEnv(HopperVectorEnv(1), config=HopperConfig())


def test_the_papers_cho2019_acts_on_frequency_and_amplitude_and_sees_the_hopper_only(tmp_path):
    """cho2019-paper: 4 actions (nu, rho per joint; the phase bias stays the preset's pi), 8
    observations (no CPG state), warm-started toward Ijspeert et al. 2007's limb oscillators
    at drive 3 (0.6 Hz, 0.524 rad), which lie inside the action ranges."""
    from cpg_actor.robots.hopper.agents import ijspeert_2007_parameters
    from cpg_actor.robots.hopper.cho2019 import PAPER_PARAMETER_RANGES, parameters_to_action

    np.testing.assert_allclose(ijspeert_2007_parameters(), [0.6, 0.6, 0.524, 0.524])
    target = parameters_to_action(ijspeert_2007_parameters(), PAPER_PARAMETER_RANGES)
    assert np.abs(target).max() < 0.9
    runner = Runner(config("cho2019-paper"), tmp_path / "run", tensorboard=False)
    env = runner.env.unwrapped
    assert env.single_action_space.shape == (4,) and env.single_observation_space.shape == (8,)
    losses = runner.run_warm_start()
    assert losses[-1] < 1e-3 * losses[0]
    obs, _ = env.reset(seed=5)
    for _ in range(30):
        obs, _, _, _, info = env.step(np.tile(target, (4, 1)))
    np.testing.assert_allclose(mean_action(runner, obs), np.tile(target, (4, 1)), atol=0.05)
    np.testing.assert_allclose(info["cpg_parameters"][:, 4], np.pi)
    np.testing.assert_allclose(info["cpg_parameters"][:, :4], [[0.6, 0.6, 0.524, 0.524]] * 4)
    with pytest.raises(ValueError, match=r"shape \(4, 4\) \(CPG parameters nu_HFE"):
        env.step(np.zeros((4, 5)))
    runner.learn()  # PPO trains on it end to end
    assert runner.global_step == runner.config.total_steps
    runner.close()


def test_with_a_start_gait_cho_is_warm_started_toward_its_parameters_and_runs_its_cpg(tmp_path):
    """cho2019-warm's defaults start it from the same gait as the CPG-Actor: the target is the
    gait's frequency, amplitude and phase bias, and the CPG inside the env has its a and w."""
    from cpg_actor.agents.start_gait import hopper_gait_parameters

    path = tmp_path / "gait.yaml"
    path.write_text(
        "robot: hopper\nfitness: 1.0\nsteps: 0\nseed: 0\ncpg_initial:\n"
        "  frequency: [1.8, 1.8]\n  amplitude: [0.4, 0.5]\n  convergence: 12.0\n"
        "  coupling_weight: 6.0\n  phase_bias: [[0.0, -0.5], [0.5, 0.0]]\n"
    )
    target = action_to_parameters(reference_action(str(path)))
    np.testing.assert_allclose(target, hopper_gait_parameters({"frequency": [1.8, 1.8],
        "amplitude": [0.4, 0.5], "phase_bias": [[0.0, -0.5], [0.5, 0.0]]}), rtol=1e-6)  # fmt: skip
    run = config("cho2019-warm")
    run.agent_config.start_gait = str(path)
    runner = Runner(run, tmp_path / "run", tensorboard=False)
    values = runner.env.unwrapped.cpg.parametrisation.values()
    assert values["convergence"].tolist() == [12.0, 12.0]
    assert float(values["coupling_weight"][0, 1].detach()) == 6.0
    runner.close()
    # the packaged gait is the default of cho2019-warm (and not of the paper's baseline)
    from cpg_actor.config import compose_config

    assert compose_config(values={"agent": "cho2019-warm"}).agent_config.start_gait == "search"
    assert compose_config(values={"agent": "cho2019-paper"}).agent_config.start_gait == ""


@pytest.mark.slow
def test_mlp_warm_clones_the_start_gait_and_hops_with_it(tmp_path):
    """mlp-warm: behaviour cloning of the start gait's joint commands (with the executed
    commands perturbed, so that the clone recovers from its own errors); the cloned MLP, run
    deterministically, hops: at least half the open-loop gait's hop height, and far above the
    standing MLP it starts as."""
    from cpg_actor.agents.warm_start import collect_gait

    run = config("mlp-warm", rollout_steps=500, epochs=100, action_noise=0.1)
    run.agent_config.start_gait = "search"
    run.env = HopperConfig()
    run.eval_interval, run.eval_episodes = 1, 3
    runner = Runner(run, tmp_path / "run", tensorboard=False)
    standing = runner.run_evaluation()["eval/hop_height"]
    losses = runner.run_warm_start()
    assert losses[-1] < 0.05 * losses[0]
    cloned = runner.run_evaluation()["eval/hop_height"]
    env = make_env(run, runner.robot, 2, 1)
    observations, commands = collect_gait(env, run.agent_config, runner.robot, 200, seed=5)
    assert observations.shape == (400, 8) and commands.shape == (400, 2)
    env.close()
    cpg = Runner(TrainConfig(**{**run.__dict__, "agent": "cpg-actor-open-loop"}), tensorboard=False)
    gait = cpg.run_evaluation()["eval/hop_height"]
    assert gait > 0.3 and cloned > 0.5 * gait and cloned > 2 * standing, (standing, cloned, gait)
    runner.close()
    cpg.close()
