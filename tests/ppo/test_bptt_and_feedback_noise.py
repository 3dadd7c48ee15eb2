"""Beyond the paper's one-step gradient: k-step replay of the CPG state (``ppo.bptt_steps``)
and exploration noise on the feedback (``agent_config.feedback_noise``)."""

import pytest
import torch

from cpg_actor.agents.base import gaussian_log_prob
from cpg_actor.config import TrainConfig
from cpg_actor.ppo import PPOConfig
from cpg_actor.ppo.algorithm import replay_states
from cpg_actor.training.runner import Runner

from .fake_env import FakeConfig, FakeHopperVectorEnv


def collected(agent="cpg-actor", bptt_steps=1, feedback_noise=0.0, **env):
    env_config = FakeConfig(**env)
    config = TrainConfig(
        agent=agent,
        num_envs=3,
        total_steps=3 * 16 * 4,
        ppo=PPOConfig(num_steps=16, num_epochs=2, num_minibatches=2, bptt_steps=bptt_steps),
        env=env_config,
        eval_interval=0,
    )
    config.agent_config.feedback_noise = feedback_noise
    runner = Runner(config, env=FakeHopperVectorEnv(3, env_config), tensorboard=False)
    runner.start_episodes()
    runner.collect()
    return runner


def window_batch(storage, k):
    batch = {name: value.flatten(0, 1) for name, value in storage.windows(k).items()}
    batch["states"] = storage.states.flatten(0, 1)
    return batch


@pytest.mark.parametrize("feedback_noise", [0.0, 0.2])
def test_replayed_states_equal_the_stored_ones_across_episode_starts(feedback_noise):
    """Before any update, replaying k - 1 steps from the state k - 1 steps earlier gives the
    stored state, episode starts (every 5 steps, falls at random) included: to float32
    rounding (the replay batches the steps otherwise, and another CPU rounds otherwise), so
    within 1e-5 of each state field's magnitude (the phase grows to about 30 rad)."""
    runner = collected(feedback_noise=feedback_noise, episode_steps=5, fall_probability=0.1)
    storage = runner.storage
    assert (storage.truncated + storage.terminated).sum() > 0
    stored = storage.states.flatten(0, 1)  # (samples, fields, oscillators)
    scale = stored.abs().amax(dim=(0, 2), keepdim=True)
    for k in (2, 4, 7):
        with torch.no_grad():
            replayed = replay_states(runner.agent, window_batch(storage, k))
        error = (replayed - stored).abs()
        assert (error <= 1e-5 * scale).all(), (error / scale).max()


def test_the_k_step_gradient_is_backpropagation_through_k_cpg_steps():
    """The replayed state's gradient with respect to the CPG vector V equals the one of an
    explicit k-step loop from the stored state; k = 1 gives none (the stored state is a
    constant: the paper's one-step gradient), and longer windows give larger ones."""
    runner = collected(episode_steps=1000, fall_probability=0.0)
    agent, storage = runner.agent, runner.storage
    vector = agent.cpg.parametrisation.vector
    t, k = 12, 5

    def gradient(state):
        (grad,) = torch.autograd.grad(state[..., 0, :].sum(), vector)  # the phases
        return grad

    batch = window_batch(storage, k)
    rows = slice(t * 3, (t + 1) * 3)  # the 3 envs at step t
    replayed = replay_states(agent, {name: value[rows] for name, value in batch.items()})
    state = storage.states[t - k + 1]
    for s in range(t - k + 2, t + 1):
        state = agent.actor(storage.observations[s - 1], state).next_state
    torch.testing.assert_close(gradient(replayed), gradient(state))
    assert replay_states(agent, {"states": storage.states[t]}).requires_grad is False
    norms = [gradient(replay_states(agent, {n: v[rows] for n, v in window_batch(
        storage, k).items()})).norm() for k in (2, 4, 8)]  # fmt: skip
    assert 0 < norms[0] < norms[1] < norms[2]


def test_bptt_update_runs_and_its_settings_are_checked():
    runner = collected(bptt_steps=4)
    before = runner.agent.cpg.parametrisation.vector.detach().clone()
    stats = runner.ppo.update(runner.storage)
    assert stats["num_minibatch_updates"] == 4
    assert not torch.equal(before, runner.agent.cpg.parametrisation.vector)
    with pytest.raises(ValueError, match=r"bptt_steps.*<= ppo.num_steps"):
        PPOConfig(num_steps=8, bptt_steps=9).validate()
    with pytest.raises(ValueError, match="bptt_steps"):
        PPOConfig(bptt_steps=0).validate()
    with pytest.raises(ValueError, match="needs an agent with a recurrent state.*'mlp'"):
        collected(agent="mlp", bptt_steps=2)


def test_sampled_feedback_is_stored_after_the_action_and_scored_with_it():
    runner = collected(feedback_noise=0.2)
    agent, storage = runner.agent, runner.storage
    n = agent.cpg.num_oscillators
    assert agent.sample_dim == agent.action_dim + 2 * n
    assert storage.actions.shape[-1] == agent.sample_dim
    std = agent.feedback_log_std.exp()
    torch.testing.assert_close(std, 0.2 * torch.tensor([4.0, 4.0, 25.0, 25.0]))
    obs, state, sample = (x[3] for x in (storage.observations, storage.states, storage.actions))
    with torch.no_grad():
        feedback = sample[:, agent.action_dim :]
        out = agent.actor(obs, state, feedback)
        expected = gaussian_log_prob(sample[:, : agent.action_dim], out.mean, out.std).sum(
            -1
        ) + gaussian_log_prob(feedback, agent.feedback_mean(obs), std).sum(-1)
        torch.testing.assert_close(storage.log_probs[3], expected)
        log_prob = agent.evaluate(obs, state, sample)[0]
    torch.testing.assert_close(log_prob, expected)
    # the feedback was really sampled (not the MLP's mean) and the env got only the action
    assert (feedback - agent.feedback_mean(obs)).abs().mean() > 0.05
    runner.policy.reset(3)
    step = runner.policy.act(runner.rollout.obs, deterministic=True)
    assert step.action.shape == (3, agent.action_dim)
    torch.testing.assert_close(step.agent.action[:, agent.action_dim :], step.agent.mean[:, 2:])


def test_feedback_noise_gives_the_feedback_network_a_gradient_of_its_own():
    """The feedback MLP's gradient through the one-step lever dx/dxi is tiny; with sampled
    feedback its own likelihood gives it one orders of magnitude larger."""
    grads = {}
    for noise in (0.0, 0.2):
        runner = collected(feedback_noise=noise)
        storage, agent = runner.storage, runner.agent
        obs, states, actions = (
            getattr(storage, f).flatten(0, 1) for f in ("observations", "states", "actions")
        )
        log_prob = agent.evaluate(obs, states, actions)[0]
        weight = agent.feedback[-1].weight
        (grad,) = torch.autograd.grad((log_prob * storage.advantages.flatten()).mean(), weight)
        grads[noise] = grad.norm().item()
    assert grads[0.2] > 100 * grads[0.0] > 0


def test_feedback_noise_needs_feedback():
    with pytest.raises(ValueError, match="feedback_noise needs an agent with feedback"):
        collected(agent="cpg-actor-open-loop", feedback_noise=0.1)
