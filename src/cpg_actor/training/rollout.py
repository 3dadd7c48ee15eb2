"""PPO's data collection: ``ppo.num_steps`` control steps in every training env with the
policy's sampled actions, the CPG state carried per env, into the rollout storage.

The episodes in progress (the env's state, the last observation, every env's CPG state, the
episode statistics and the discounted returns of the reward scaling) are saved in checkpoints
(:meth:`Rollout.state`) and continued on resume (:meth:`Rollout.restore`), so a checkpoint
neither resets nor cuts an episode.
"""

from __future__ import annotations

import time
from typing import Any

import torch

from cpg_actor.config import TrainConfig
from cpg_actor.robots.common.torch_env import EnvStep
from cpg_actor.training.build import PPORun
from cpg_actor.training.episodes import EpisodeLog, EpisodeStats
from cpg_actor.training.policy import PolicyStep


class NonFiniteActionsError(RuntimeError):
    """The policy's actions became NaN or inf during a rollout."""


class Rollout:
    """Collects the rollouts of one run's training envs (see the module docstring).

    ``sync_free``: the rollout never waits for the device (no host sync per control step) when
    the env hands over device tensors itself (MJX) or torch runs on an accelerator; the
    episode log and the check of the actions then sync once per rollout.
    """

    def __init__(self, config: TrainConfig, run: PPORun) -> None:
        self.config = config
        self.env = run.env
        self.agent = run.agent
        self.policy = run.policy
        self.reward_normalizer = run.reward_normalizer
        self.storage = run.storage
        self.device = run.device
        self.sync_free = self.device.type != "cpu" or self.env.has_tensor_face
        self.episodes = EpisodeLog(config.num_envs, deferred=self.sync_free)
        self.obs: torch.Tensor | None = None  # every env's last observation
        self.started = False  # the episodes have begun (start or restore)
        self.simulation_time = 0.0  # seconds in env.step during the last rollout

    def start(self, seed: int) -> None:
        """Reset every env (with ``seed``) and every CPG state: new episodes."""
        self.obs, _ = self.env.reset(seed=seed)
        self.policy.reset(self.config.num_envs)
        self.reward_normalizer.reset()
        self.episodes.running = EpisodeStats.zeros(self.config.num_envs, self.device)
        self.started = True

    def normalize(self, obs: torch.Tensor) -> torch.Tensor:
        """The critic's input for ``obs``, the normaliser left as it is."""
        return self.policy.normalize(obs, update=False)

    @torch.no_grad()
    def collect(self) -> dict[str, float]:
        """One rollout into the storage, with its returns and advantages computed."""
        self.begin()
        for _ in range(self.config.ppo.num_steps):
            self.step()
        return self.finish()

    def begin(self) -> None:
        """Before a rollout's first step: the storage emptied, the counters at zero."""
        self.storage.clear()
        self.simulation_time = 0.0
        # sync-free: whether every action so far was finite, on the device, checked once below
        self._finite_actions = torch.ones((), dtype=torch.bool, device=self.device)

    @torch.no_grad()
    def finish(self) -> dict[str, float]:
        """After a rollout's last step: the episode log flushed, the actions checked, the
        returns and advantages computed."""
        cfg = self.config
        if self.sync_free:  # the rollout's one wait for the device, with the episode log's
            self.episodes.flush()
            if not bool(self._finite_actions):
                raise NonFiniteActionsError(
                    "the policy's actions became NaN or inf during the rollout"
                )
        last_values = self.agent.value(self.normalize(self.obs), self.policy.state)
        self.storage.compute_returns(last_values, cfg.ppo.gamma, cfg.ppo.gae_lambda)
        return {"simulation_time": self.simulation_time}

    def step(self) -> None:
        """One control step in every env: act, step, store, track episodes. With
        :attr:`sync_free` it never waits for the device (tested on JAX's CPU backend)."""
        acted = self.act()
        start = time.perf_counter()
        if self.sync_free:  # the env's check of the actions would wait: checked per rollout
            out = self.env.step(acted.action, check_finite=False)
        else:
            out = self.env.step(acted.action)
        self.simulation_time += time.perf_counter() - start
        self.record(acted, out)

    @torch.no_grad()
    def act(self) -> PolicyStep:
        """The sampled actions of every env for its last observation (the CPG state
        advances)."""
        acted = self.policy.act(
            self.obs, deterministic=False, update_normalizer=True, tensor_action=True
        )
        if self.sync_free:
            self._finite_actions &= torch.isfinite(acted.action).all()
        return acted

    @torch.no_grad()
    def record(self, acted: PolicyStep, out: EnvStep) -> None:
        """Store the step ``acted`` led to (``out``, the env's answer), track the episodes."""
        cfg = self.config
        step = acted.agent
        done = out.terminated | out.truncated
        final_values = torch.zeros(cfg.num_envs, device=self.device)
        bootstrap = out.truncated & ~out.terminated
        if self.sync_free:  # no sync with the host: every env's, kept where cut
            cut_values = self.agent.value(self.normalize(out.final_obs), step.next_state)
            final_values = torch.where(bootstrap, cut_values, final_values)
        elif bootstrap.any():  # the value of a cut episode's last state
            rows = bootstrap.nonzero().squeeze(-1)
            final_obs = self.normalize(out.final_obs[rows])
            final_values[rows] = self.agent.value(final_obs, step.next_state[rows])
        rewards = out.reward.to(torch.float32)
        if cfg.ppo.normalize_rewards:
            rewards = self.reward_normalizer(rewards, done)
        self.storage.add_policy_step(acted, rewards, out.terminated, out.truncated, final_values)
        self.policy.end_episodes(done)
        self.obs = out.obs
        self.episodes.track(out, done)

    def state(self) -> dict[str, Any] | None:
        """The episodes in progress; None before they start or if the env cannot save its
        state (a resumed run then starts new episodes)."""
        if not self.started or not self.env.saves_state:
            return None
        return {
            "env": self.env.get_state(),
            "obs": self.obs.cpu().clone(),
            "agent_state": self.policy.state.cpu().clone(),
            "statistics": self.episodes.running.state_dict(),
            "discounted_returns": self.reward_normalizer.discounted.cpu().clone(),
        }

    def restore(self, state: dict[str, Any]) -> None:
        """Continue the episodes saved by :meth:`state`."""
        try:
            self.env.set_state(state["env"])
            obs, agent_state = state["obs"], state["agent_state"]
            if obs.shape != (self.config.num_envs, self.env.single_observation_space.shape[0]):
                raise ValueError(f"observations of shape {tuple(obs.shape)}")
            if agent_state.shape != (self.config.num_envs, *self.agent.state_shape):
                raise ValueError(f"agent states of shape {tuple(agent_state.shape)}")
            running = EpisodeStats.from_state_dict(state["statistics"], self.device)
            discounted = state["discounted_returns"]
            if discounted.shape != self.reward_normalizer.discounted.shape:
                raise ValueError(f"discounted returns of shape {tuple(discounted.shape)}")
            self.reward_normalizer.discounted.copy_(discounted)
        except (KeyError, TypeError, AttributeError, RuntimeError, ValueError) as error:
            raise ValueError(
                f"the checkpoint's episodes do not fit this run's environments: {error}"
            ) from None
        self.episodes.running = running
        self.obs = obs.to(self.device).clone()
        self.policy.state = agent_state.to(self.device).clone()
        self.started = True
