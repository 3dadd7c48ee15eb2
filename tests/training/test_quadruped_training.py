"""Training on the ANYmal B quadruped (`--robot anymal`): the CPG-Actor (8 oscillators driving
12 joints), its open-loop variant and the MLP train through the same runner as the hopper; the
run's config names the robot and resumes; the hopper-only agents say so."""

import json

import numpy as np
import pytest
import torch

from cpg_actor.cli import main
from cpg_actor.config import TrainConfig, apply_dict, parse_override
from cpg_actor.ppo import PPOConfig
from cpg_actor.robots.anymal.vector import AnymalVectorEnv
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.training.runner import Runner
from tiny import tiny_config


def anymal_config(agent: str, eval_interval: int = 0, **fields) -> TrainConfig:
    config = tiny_config(agent, **fields)
    config.eval_interval = eval_interval
    apply_dict(config, {"robot": "anymal", "env": {"episode_seconds": 0.2}}, "")
    return config


@pytest.mark.parametrize("agent", ["cpg-actor", "cpg-actor-open-loop", "mlp"])
def test_every_agent_trains_on_the_quadruped(agent):
    runner = Runner(anymal_config(agent, eval_interval=2, eval_episodes=2), tensorboard=False)
    try:
        assert isinstance(runner.env.unwrapped, AnymalVectorEnv)
        before = {k: v.clone() for k, v in runner.agent.state_dict().items()}
        runner.learn()
        after = runner.agent.state_dict()
        assert all(torch.isfinite(v).all() for v in after.values())
        assert any(not torch.equal(before[k], after[k]) for k in before)
        evaluation = runner.run_evaluation()
        assert np.isfinite(evaluation["eval/return"])
        assert 0.0 <= evaluation["eval/fell"] <= 1.0
        if agent.startswith("cpg-actor"):
            assert runner.agent.cpg.num_oscillators == 8
            assert runner.agent.joint_map(torch.zeros(1, 8)).shape == (1, 12)
    finally:
        runner.close()


def test_robot_selects_the_env_config_and_bad_combinations_are_refused():
    config = TrainConfig()
    apply_dict(config, parse_override("robot=anymal"), "")
    assert isinstance(config.env, QuadrupedConfig)
    apply_dict(config, parse_override("env.command_range=[0.5, 0.5]"), "")
    assert tuple(config.env.command_range) == (0.5, 0.5)
    config.validate()
    again = TrainConfig.from_dict(config.to_dict())
    assert again.robot == "anymal" and again.env == config.env
    with pytest.raises(ValueError, match="for hopper only; on robot .anymal. use one of cpg"):
        TrainConfig.from_dict({**config.to_dict(), "agent": "cho2019"}).validate()
    with pytest.raises(ValueError, match="unknown robot"):
        apply_dict(TrainConfig(), parse_override("robot=biped"), "")
    with pytest.raises(ValueError, match="cpg_gait must be one of"):
        apply_dict(config, parse_override("agent_config.cpg_gait=gallop"), "")
        config.validate()


def test_cli_trains_a_pace_resumes_and_logs_the_robots_metrics(tmp_path, capsys):
    run = tmp_path / "run"
    args = ["train", "--robot", "anymal", "--num-envs", "2", "--total-steps", "32",
            "--set", "ppo.num_steps=8", "--set", "ppo.num_minibatches=2",
            "--set", "ppo.num_epochs=1", "--set", "eval_interval=0",
            "--set", "env.episode_seconds=0.1", "--set", "agent_config.cpg_gait=pace",
            "--set", "checkpoint_interval=1", "--run-dir", str(run), "--no-progress"]  # fmt: skip
    assert main(args) == 0
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    assert any(row.get("charts/fell") is not None for row in rows)
    assert any(row.get("charts/speed_error") is not None for row in rows)
    # the quadruped's reward terms, as the hopper's r1..r5: metrics.jsonl and TensorBoard
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    terms = {f"reward_terms/{name}" for name in QuadrupedConfig().reward_scales}
    assert terms <= set(rows[-1])
    events = EventAccumulator(str(run / "tensorboard"))
    events.Reload()
    assert terms <= set(events.Tags()["scalars"])
    assert main(["train", "--run-dir", str(run), "--resume", "--total-steps", "48",
                 "--no-progress"]) == 0  # fmt: skip
    assert "anymal-mujoco" in capsys.readouterr().out
    assert main(["train", "--robot", "anymal", "--sim", "pybullet", "--run-dir",
                 str(tmp_path / "other")]) == 2  # fmt: skip
    assert "--sim pybullet: the anymal runs on mujoco, mjx" in capsys.readouterr().err
    assert not (tmp_path / "other").exists()


def test_bad_quadruped_config_values_say_what_is_accepted():
    for override, message in (
        ("env.command_range=0.5", "command_range must be \\[low, high\\]"),
        ("env.command_range=[1.0, 0.0]", "low <= high"),
        ("env.reward_scales=3", "reward_scales must be a mapping"),
        ("env.reward_scales.torques=abc", "reward_scales.torques must be a finite number"),
    ):
        config = TrainConfig()
        apply_dict(config, parse_override("robot=anymal"), "")
        with pytest.raises(ValueError, match=message):
            apply_dict(config, parse_override(override), "")
    config = TrainConfig()
    apply_dict(config, parse_override("robot=hopper"), "")
    with pytest.raises(ValueError, match="has no gaits"):
        apply_dict(config, parse_override("agent_config.cpg_gait=trot"), "")
        Runner(config, tensorboard=False)


def test_the_command_drives_the_cpg_and_training_replays_it():
    """Eq. 3 on the quadruped: the CPG-Actor's drive d is the raw forward-speed command (a
    sixth row of its state), so a larger command gives larger CPG amplitudes; the rollout
    storage keeps the drive with the state and the PPO update replays the same log-probs;
    the gradient reaches the drive gains c_nu1 and c_R1. cpg_drive=False: no drive row."""
    from cpg_actor.cpg import CPGState

    runner = Runner(anymal_config("cpg-actor"), tensorboard=False)
    try:
        agent, policy = runner.agent, runner.policy
        assert agent.state_shape == (6, 8)
        obs = np.zeros((2, agent.obs_dim), dtype=np.float32)
        obs[:, agent.drive_index] = [1.0, -0.5]  # a negative command is clipped: d = 0
        policy.reset(2)
        for _ in range(30):  # the amplitudes converge towards rho(d)
            step = policy.act(obs)
        assert step.state[:, 5].tolist() == [[1.0] * 8, [0.0] * 8]
        amplitude = CPGState.from_tensor(policy.state[:, :5]).amplitude
        rho = agent.cpg.oscillator_parameters(step.state[:, 5]).amplitude
        assert torch.allclose(amplitude, rho, rtol=0.05)
        assert (amplitude[0] > amplitude[1] + 0.05).all()

        runner.start_episodes()
        runner.collect()
        storage = runner.storage
        assert (storage.states[:, :, 5] >= 0).all() and storage.states[:, :, 5].max() > 0
        log_prob = agent.evaluate(storage.observations[0], storage.states[0],
                                  storage.actions[0])[0]  # fmt: skip
        assert torch.allclose(log_prob, storage.log_probs[0], atol=1e-5)
        loss = -agent.evaluate(storage.observations[0], storage.states[0],
                               storage.actions[0])[0].mean()  # fmt: skip
        agent.zero_grad()
        loss.backward()
        parametrisation = agent.cpg.parametrisation
        grad = parametrisation.vector.grad
        for field in ("frequency_gain", "amplitude_gain"):
            entries = parametrisation.indices(field)
            assert (entries >= 0).all() and grad[entries].abs().sum() > 0, field
    finally:
        runner.close()
    config = anymal_config("cpg-actor")
    config.agent_config.cpg_drive = False
    runner = Runner(config, tensorboard=False)
    try:
        assert runner.agent.state_shape == (5, 8)
    finally:
        runner.close()


def test_a_replay_over_several_steps_uses_each_steps_own_drive():
    """ppo.bptt_steps > 1: the replayed state takes the drive of the stored state at each step
    (what observe wrote there), not the window's first one; here the command changes inside
    the window, and the replayed drive rows equal the stored ones."""
    from cpg_actor.ppo.algorithm import replay_states

    config = anymal_config("cpg-actor")
    config.ppo = PPOConfig(num_steps=8, num_epochs=1, num_minibatches=1, bptt_steps=4)
    runner = Runner(config, tensorboard=False)
    try:
        runner.start_episodes()
        runner.collect()
        storage = runner.storage
        storage.states[:, :, 5] = torch.arange(8.0)[:, None, None] / 8  # a new drive each step
        batch = {**{k: v.flatten(0, 1) for k, v in storage.windows(4).items()},
                 "states": storage.states.flatten(0, 1)}  # fmt: skip
        replayed = replay_states(runner.agent, batch)
        assert torch.equal(replayed[:, 5], storage.states.flatten(0, 1)[:, 5])
        # the CPG rows still come from the replay (they differ from the stored state where a
        # drive changed the steps before)
        assert not torch.equal(replayed[:, :5], storage.states.flatten(0, 1)[:, :5])
    finally:
        runner.close()


def test_the_leg_layout_trains_four_foot_space_oscillators():
    """agent_config.cpg_layout=leg: one oscillator per leg through the foot-space pattern; the
    untrained mean action at phase 0 and no amplitude is the nominal pose; the update moves V;
    the hopper has no such layout (the error lists its layouts)."""
    config = anymal_config("cpg-actor")
    config.agent_config.cpg_layout = "leg"
    runner = Runner(config, tensorboard=False)
    try:
        agent = runner.agent
        assert agent.cpg.num_oscillators == 4 and agent.state_shape == (6, 4)
        assert agent.joint_map is None and agent.pattern is not None
        before = agent.cpg.parametrisation.vector.detach().clone()
        runner.learn()
        assert not torch.equal(before, agent.cpg.parametrisation.vector.detach())
        scalars = agent.log_scalars()
        assert {"cpg/nu_LF", "cpg/rho_gain_RH", "cpg/phi_LF_RF"} <= set(scalars)
    finally:
        runner.close()
    hopper = tiny_config("cpg-actor")
    hopper.agent_config.cpg_layout = "leg"
    with pytest.raises(ValueError, match="cpg_layout must be one of joint on robot 'hopper'"):
        Runner(hopper, tensorboard=False)
    bad = TrainConfig()
    apply_dict(bad, parse_override("agent_config.cpg_layout=foot"), "")
    with pytest.raises(ValueError, match="cpg_layout must be one of joint on robot 'hopper'"):
        bad.validate()
