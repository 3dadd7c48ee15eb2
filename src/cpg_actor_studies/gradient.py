"""How much of the full-trajectory policy gradient a truncated CPG replay keeps.

The paper trains the CPG-Actor with no backpropagation through time: the rollout stores the
CPG state z_t and the PPO loss replays one CPG step from it, so z_t is a constant of the
loss and the gradient reaches the CPG parameters and the feedback network through one step
only. This module measures what that truncation loses on a real rollout of a policy.

For one rollout (obs o_t, stored states z_t, sampled actions a_t, Monte Carlo advantages A_t)
the PPO surrogate at ratio 1, ``J = mean_t A_t log pi(a_t | o_t, z_t(theta))``, is
differentiated with z_t(theta):

* **full**: replayed from each episode's first state through every step before t (full
  backpropagation through time; the observations stay those of the rollout: the simulator is
  not differentiated);
* **k-step** (``ppo.bptt_steps = k``; k = 1 is the paper): replayed from the stored z_{t-k+1}.

Per parameter group (the CPG's log nu, log rho, log a, w, phi; the feedback network) it
reports the cosine between the truncated and the full gradient and the ratio of their norms.
With ``agent_config.feedback_noise`` the feedback network also gets the score of its own
sampled feedback; a truncation cannot change that term, and the report says how large it is.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor

from cpg_actor.agents.base import gaussian_log_prob
from cpg_actor.api import CPGActorAgent, Policy
from cpg_actor.ppo.algorithm import replay_states
from cpg_actor.ppo.storage import RolloutStorage

# parameter group -> CPG field; "feedback" is the feedback network
CPG_GROUPS = {
    "log_nu": "frequency",
    "log_rho": "amplitude",
    "log_a": "convergence",
    "w": "coupling_weight",
    "phi": "phase_bias",
}


@dataclass
class Rollout:
    """One rollout from the envs' reset, ``(T, N, ...)`` per field."""

    storage: RolloutStorage  # observations, states, actions (samples), terminated, truncated
    advantages: Tensor  # (T, N): standardised discounted returns to go


@torch.no_grad()
def collect_rollout(policy: Policy, env, num_steps: int, seed: int, gamma: float) -> Rollout:
    """Sample ``num_steps`` control steps of ``policy`` in every env of ``env`` (a
    :class:`~cpg_actor.robots.common.torch_env.TorchVectorEnv`) from a reset with ``seed``."""
    agent = policy.agent
    n = env.num_envs
    storage = RolloutStorage(
        num_steps,
        n,
        int(env.single_observation_space.shape[0]),
        agent.sample_dim,
        tuple(agent.state_shape),
    )
    torch.manual_seed(seed)
    obs, _ = env.reset(seed=seed)
    policy.reset(n)
    rewards = torch.zeros(num_steps, n, dtype=torch.float64)
    for t in range(num_steps):
        acted = policy.act(obs, deterministic=False)
        out = env.step(acted.action)
        storage.add_policy_step(
            acted, out.reward.float(), out.terminated, out.truncated, torch.zeros(n)
        )
        rewards[t] = out.reward
        policy.end_episodes(out.terminated | out.truncated)
        obs = out.obs
    done = torch.maximum(storage.terminated, storage.truncated).double()
    returns = torch.zeros_like(rewards)
    running = torch.zeros(n, dtype=torch.float64)
    for t in reversed(range(num_steps)):
        running = rewards[t] + gamma * (1.0 - done[t]) * running
        returns[t] = running
    advantages = (returns - returns.mean()) / (returns.std() + 1e-8)
    return Rollout(storage, advantages.float())


def full_replay(agent: CPGActorAgent, storage: RolloutStorage) -> Tensor:
    """Every step's state replayed from its episode's first state, ``(T * N, *state)``
    (the k = T window, computed in one pass)."""
    state = storage.states[0]
    done = torch.maximum(storage.terminated, storage.truncated) > 0
    states = [state]
    for t in range(1, storage.num_steps):
        stepped = agent.replay_state(storage.observations[t - 1], state, storage.actions[t - 1])
        stepped = agent.keep_observed(stepped, storage.states[t])
        mask = done[t - 1].reshape(-1, *([1] * (state.dim() - 1)))
        state = torch.where(mask, storage.states[t], stepped)
        states.append(state)
    return torch.stack(states).flatten(0, 1)


def group_gradients(agent: CPGActorAgent, objective: Tensor) -> dict[str, Tensor]:
    """The gradient of ``objective`` per parameter group (see :data:`CPG_GROUPS`)."""
    parametrisation = agent.cpg.parametrisation
    params = [parametrisation.vector]
    feedback = list(agent.feedback.parameters()) if agent.feedback is not None else []
    grads = torch.autograd.grad(objective, params + feedback, allow_unused=True)
    vector_grad = grads[0] if grads[0] is not None else torch.zeros_like(parametrisation.vector)
    out = {}
    for name, field in CPG_GROUPS.items():
        index = parametrisation.indices(field).flatten()
        index = torch.unique(index[index >= 0])
        out[name] = vector_grad[index]
    if feedback:
        out["feedback"] = torch.cat(
            [
                (g if g is not None else torch.zeros_like(p)).flatten()
                for g, p in zip(grads[1:], feedback, strict=True)
            ]  # fmt: skip
        )
    return out


def surrogate(agent: CPGActorAgent, rollout: Rollout, states: Tensor) -> Tensor:
    s = rollout.storage
    obs, actions = s.observations.flatten(0, 1), s.actions.flatten(0, 1)
    log_prob = agent.evaluate(obs, states, actions)[0]
    return (rollout.advantages.flatten() * log_prob).mean()


def truncation_study(
    agent: CPGActorAgent, rollout: Rollout, ks: list[int]
) -> dict[str, dict[str, float]]:
    """``{label: {group: value}}``: for each k, ``cos/<group>`` and ``norm/<group>`` of the
    k-step gradient against the full one (labels ``"k=1"``, ...), and ``"full"`` with the
    full gradient's norms."""
    storage = rollout.storage
    full = group_gradients(agent, surrogate(agent, rollout, full_replay(agent, storage)))
    result = {"full": {f"norm/{g}": float(v.norm()) for g, v in full.items()}}
    for k in ks:
        if k == 1:
            states = storage.states.flatten(0, 1)
        else:
            batch = {name: v.flatten(0, 1) for name, v in storage.windows(k).items()}
            states = replay_states(agent, batch)
        grads = group_gradients(agent, surrogate(agent, rollout, states))
        row = {}
        for group, g in grads.items():
            reference = full[group]
            denominator = float(g.norm() * reference.norm())
            row[f"cos/{group}"] = float(g @ reference) / denominator if denominator else np.nan
            row[f"norm/{group}"] = (
                float(g.norm() / reference.norm()) if reference.norm() > 0 else np.nan
            )
        result[f"k={k}"] = row
    return result


def feedback_score_share(agent: CPGActorAgent, rollout: Rollout) -> float | None:
    """With sampled feedback: the norm of the feedback network's gradient from the score of
    its own samples, over that from the one-step lever through the CPG (None without)."""
    if agent.feedback_log_std is None:
        return None
    s = rollout.storage
    obs, states, samples = (
        s.observations.flatten(0, 1),
        s.states.flatten(0, 1),
        s.actions.flatten(0, 1),
    )
    weights = rollout.advantages.flatten()
    feedback = samples[:, agent.action_dim :]
    lever = agent.actor(obs, states)  # the CPG step with the feedback's mean: the lever
    own = gaussian_log_prob(feedback, agent.feedback_mean(obs), agent.feedback_log_std.exp())
    through_cpg = gaussian_log_prob(samples[:, : agent.action_dim], lever.mean, lever.std)
    params = list(agent.feedback.parameters())
    score = torch.autograd.grad((weights * own.sum(-1)).mean(), params)
    pathwise = torch.autograd.grad((weights * through_cpg.sum(-1)).mean(), params)
    norm = lambda gs: float(torch.cat([g.flatten() for g in gs]).norm())  # noqa: E731
    return norm(score) / norm(pathwise)
