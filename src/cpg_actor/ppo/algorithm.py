"""The PPO update (Schulman et al. 2017): clipped surrogate, clipped value loss, entropy bonus.

Each minibatch replays one agent step from the stored (normalised observation, recurrent
state): for the CPG-Actor that is one CPG step from the stored CPG state (paper III-B).
"""

from __future__ import annotations

import math

import torch
from torch import Tensor

from cpg_actor.agents.base import Agent
from cpg_actor.ppo.config import PPOConfig
from cpg_actor.ppo.storage import RolloutStorage


class NonFiniteLossError(FloatingPointError):
    """A loss, gradient, parameter or policy output became NaN/inf; the update was undone."""


def gaussian_kl(mu_old: Tensor, std_old: Tensor, mu: Tensor, std: Tensor) -> Tensor:
    """KL(old || new) of diagonal Gaussians, summed over action dimensions, ``(B,)``."""
    return (
        torch.log(std / std_old) + (std_old**2 + (mu_old - mu) ** 2) / (2.0 * std**2) - 0.5
    ).sum(-1)


class PPO:
    def __init__(self, agent: Agent, config: PPOConfig) -> None:
        self.agent = agent
        self.config = config
        self.learning_rate = config.learning_rate
        self.optimizer = torch.optim.Adam(
            agent.parameters(), lr=config.learning_rate, eps=config.adam_eps
        )

    def set_learning_rate(self, lr: float) -> None:
        self.learning_rate = lr
        for group in self.optimizer.param_groups:
            group["lr"] = lr

    def schedule(self, iteration: int, num_iterations: int) -> None:
        """Linear decay to 0 over the run; the adaptive rule acts inside :meth:`update`."""
        if self.config.lr_schedule == "linear":
            self.set_learning_rate(self.config.learning_rate * (1.0 - iteration / num_iterations))

    def _parameters(self) -> list[torch.Tensor]:
        return [p for group in self.optimizer.param_groups for p in group["params"]]

    def _undo(self, snapshot: list[torch.Tensor], reason: str) -> NonFiniteLossError:
        """Put the parameters back to ``snapshot``; the error to raise."""
        with torch.no_grad():
            for p, old in zip(self._parameters(), snapshot, strict=True):
                p.copy_(old)
        return NonFiniteLossError(
            f"{reason} (learning rate {self.learning_rate:g}); the update was undone"
        )

    @torch.no_grad()
    def _outputs_are_finite(self, storage: RolloutStorage) -> bool:
        """The updated policy's mean, std and value on every stored (observation, state)."""
        # flattened in order: no random permutation, so training's RNG stream is untouched
        obs, states = (getattr(storage, name).flatten(0, 1) for name in ("observations", "states"))
        out = self.agent.actor(obs, states)
        value, mean, std = self.agent.value(obs, states), out.mean, out.std
        return all(bool(torch.isfinite(t).all()) for t in (value, mean, std))

    def update(self, storage: RolloutStorage) -> dict[str, float]:
        cfg = self.config
        stats: dict[str, list[float]] = {
            k: [] for k in ("policy_loss", "value_loss", "entropy", "approx_kl", "clipfrac", "kl")
        }
        early_stop = False
        # a finite loss with a huge step can still break the policy: every update is checked
        # (parameters after each step, outputs at the end) and undone if it did, so nothing
        # non-finite is ever used, logged or saved
        snapshot = [p.detach().clone() for p in self._parameters()]
        for _ in range(cfg.num_epochs):
            for batch in storage.minibatches(cfg.num_minibatches):
                log_prob, entropy, value, mean, std = self.agent.evaluate(
                    batch["observations"], batch["states"], batch["actions"]
                )
                log_ratio = log_prob - batch["log_probs"]
                ratio = log_ratio.exp()
                with torch.no_grad():
                    approx_kl = ((ratio - 1.0) - log_ratio).mean()  # k3 estimator (CleanRL)
                    clipfrac = ((ratio - 1.0).abs() > cfg.clip_ratio).float().mean()
                    kl = gaussian_kl(batch["action_mean"], batch["action_std"], mean, std).mean()
                if cfg.lr_schedule == "adaptive":
                    kl_value = kl.item()
                    if kl_value > 2.0 * cfg.desired_kl:
                        self.set_learning_rate(max(cfg.min_learning_rate, self.learning_rate / 1.5))
                    elif 0.0 < kl_value < 0.5 * cfg.desired_kl:
                        self.set_learning_rate(min(cfg.max_learning_rate, self.learning_rate * 1.5))

                advantages = batch["advantages"]
                if cfg.normalize_advantages and advantages.numel() > 1:
                    advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)
                surrogate = -advantages * ratio
                surrogate_clipped = -advantages * ratio.clamp(
                    1.0 - cfg.clip_ratio, 1.0 + cfg.clip_ratio
                )
                policy_loss = torch.max(surrogate, surrogate_clipped).mean()

                returns, old_values = batch["returns"], batch["values"]
                if cfg.clip_value_loss:
                    value_clipped = old_values + (value - old_values).clamp(
                        -cfg.clip_ratio, cfg.clip_ratio
                    )
                    value_loss = (
                        0.5
                        * torch.max((value - returns) ** 2, (value_clipped - returns) ** 2).mean()
                    )
                else:
                    value_loss = 0.5 * ((value - returns) ** 2).mean()
                entropy_mean = entropy.mean()
                loss = (
                    policy_loss + cfg.value_loss_coef * value_loss - cfg.entropy_coef * entropy_mean
                )
                if not torch.isfinite(loss):
                    raise self._undo(
                        snapshot,
                        f"non-finite PPO loss (policy {policy_loss.item()}, value "
                        f"{value_loss.item()}, entropy {entropy_mean.item()})",
                    )

                self.optimizer.zero_grad(set_to_none=True)
                loss.backward()
                grad_norm = torch.nn.utils.clip_grad_norm_(
                    self.agent.parameters(), cfg.max_grad_norm
                )
                if not torch.isfinite(grad_norm):
                    raise self._undo(snapshot, "non-finite gradient norm")
                self.optimizer.step()
                if not all(bool(torch.isfinite(p).all()) for p in self._parameters()):
                    raise self._undo(snapshot, "an optimiser step made the parameters non-finite")

                stats["policy_loss"].append(policy_loss.item())
                stats["value_loss"].append(value_loss.item())
                stats["entropy"].append(entropy_mean.item())
                stats["approx_kl"].append(approx_kl.item())
                stats["clipfrac"].append(clipfrac.item())
                stats["kl"].append(kl.item())
                if cfg.target_kl is not None and approx_kl.item() > cfg.target_kl:
                    early_stop = True
                    break
            if early_stop:
                break

        if not self._outputs_are_finite(storage):
            raise self._undo(snapshot, "the updated policy gives non-finite actions or values")
        values = storage.values.flatten()
        returns = storage.returns.flatten()
        var_returns = returns.var().item()
        explained = (
            math.nan if var_returns == 0 else 1.0 - (returns - values).var().item() / var_returns
        )
        result = {k: sum(v) / len(v) for k, v in stats.items() if v}
        result.update(
            explained_variance=explained,
            learning_rate=self.learning_rate,
            early_stop=float(early_stop),
            num_minibatch_updates=float(len(stats["policy_loss"])),
        )
        return result
