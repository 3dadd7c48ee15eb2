"""The PPO update (Schulman et al. 2017): clipped surrogate, clipped value loss, entropy bonus.

Each minibatch replays one agent step from the stored (normalised observation, recurrent
state): for the CPG-Actor that is one CPG step from the stored CPG state (paper III-B), or,
with ``ppo.bptt_steps = k``, k CPG steps from the state stored k - 1 steps earlier.
"""

from __future__ import annotations

import math
import os
import shutil

import torch
from torch import Tensor

from cpg_actor.agents.base import Agent
from cpg_actor.ppo import train_step
from cpg_actor.ppo.config import PPOConfig
from cpg_actor.ppo.optimizer import (
    adam_step,
    adaptive_learning_rate,
    clip_grad_norm_,
    cpg_learning_rate,
)
from cpg_actor.ppo.storage import RolloutStorage


class NonFiniteLossError(FloatingPointError):
    """A loss, gradient, parameter or policy output became NaN/inf; the update was undone."""


def gaussian_kl(mu_old: Tensor, std_old: Tensor, mu: Tensor, std: Tensor) -> Tensor:
    """KL(old || new) of diagonal Gaussians, summed over action dimensions, ``(B,)``."""
    return (
        torch.log(std / std_old) + (std_old**2 + (mu_old - mu) ** 2) / (2.0 * std**2) - 0.5
    ).sum(-1)


def replay_states(agent: Agent, batch: dict[str, Tensor]) -> Tensor:
    """The recurrent state each sample's step starts from, as the PPO loss sees it.

    Without window fields (``ppo.bptt_steps = 1``, the paper): the stored state, a constant,
    so the gradient reaches the CPG through one step only. With them (``bptt_steps = k``):
    the state recomputed with the current parameters from the stored state ``k - 1`` steps
    earlier (:meth:`RolloutStorage.windows`), through the stored observations and sampled
    actions of those steps: truncated backpropagation through time over k CPG steps. Where
    an episode began inside the window (or the window reaches before the rollout), the
    stored state at that step is used from there on."""
    if "window_states" not in batch:
        return batch["states"]
    state = batch["window_states"]
    restart = batch["window_restart"] > 0
    for j in range(restart.shape[1]):
        stored = batch["window_restart_states"][:, j]
        stepped = agent.replay_state(
            batch["window_observations"][:, j], state, batch["window_actions"][:, j]
        )
        stepped = agent.keep_observed(stepped, stored)  # e.g. this step's drive
        mask = restart[:, j].reshape(-1, *([1] * (state.dim() - 1)))
        state = torch.where(mask, stored, stepped)
    return state


def ppo_loss(agent: Agent, batch: dict[str, Tensor], config: PPOConfig) -> tuple[Tensor, Tensor]:
    """The PPO loss of one minibatch and its statistics, ``(loss, stats)``, ``stats`` being
    ``(policy_loss, value_loss, entropy, approx_kl, clipfrac, kl)`` (detached).

    Clipped surrogate (Schulman et al. 2017, eq. 7) on per-minibatch normalised advantages,
    value loss clipped as in Baselines ppo2 (``clip_value_loss``), entropy bonus. Pure: the
    same inputs give the same outputs, so it can be compiled (``ppo.compile``)."""
    cfg = config
    log_prob, entropy, value, mean, std = agent.evaluate(
        batch["observations"], replay_states(agent, batch), batch["actions"]
    )
    log_ratio = log_prob - batch["log_probs"]
    ratio = log_ratio.exp()
    with torch.no_grad():
        approx_kl = ((ratio - 1.0) - log_ratio).mean()  # k3 estimator (CleanRL)
        clipfrac = ((ratio - 1.0).abs() > cfg.clip_ratio).float().mean()
        kl = gaussian_kl(batch["action_mean"], batch["action_std"], mean, std).mean()
    advantages = batch["advantages"]
    if cfg.normalize_advantages and advantages.numel() > 1:
        advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)
    surrogate = -advantages * ratio
    surrogate_clipped = -advantages * ratio.clamp(1.0 - cfg.clip_ratio, 1.0 + cfg.clip_ratio)
    policy_loss = torch.max(surrogate, surrogate_clipped).mean()
    returns, old_values = batch["returns"], batch["values"]
    if cfg.clip_value_loss:
        value_clipped = old_values + (value - old_values).clamp(-cfg.clip_ratio, cfg.clip_ratio)
        value_loss = 0.5 * torch.max((value - returns) ** 2, (value_clipped - returns) ** 2).mean()
    else:
        value_loss = 0.5 * ((value - returns) ** 2).mean()
    entropy_mean = entropy.mean()
    loss = policy_loss + cfg.value_loss_coef * value_loss - cfg.entropy_coef * entropy_mean
    stats = torch.stack([policy_loss, value_loss, entropy_mean, approx_kl, clipfrac, kl])
    return loss, stats.detach()


STATS = ("policy_loss", "value_loss", "entropy", "approx_kl", "clipfrac", "kl")


@torch.no_grad()
def outputs_are_finite(agent: Agent, observations: Tensor, states: Tensor) -> Tensor:
    """A 0-dim bool tensor: the agent's action mean, std and value are finite on every
    ``(observation, state)`` row. Pure, so it can be compiled (``ppo.compile``)."""
    out = agent.actor(observations, states)
    value = agent.value(observations, states)
    return torch.stack([torch.isfinite(t).all() for t in (value, out.mean, out.std)]).all()


def cpp_compiler() -> str | None:
    """The C++ compiler torch.compile would use on the CPU, or None."""
    for name in (os.environ.get("CXX"), "g++", "c++", "clang++"):
        if name and shutil.which(name):
            return name
    return None


_compiles_forgotten = 0  # how many times PPO made dynamo forget every compiled function


def forget_compiled() -> None:
    """``torch.compiler.reset()``, counted by :func:`compile_generation`."""
    global _compiles_forgotten
    torch.compiler.reset()
    _compiles_forgotten += 1


def compile_generation() -> int:
    """A count that changes whenever a new :class:`PPO` with ``compile`` makes dynamo
    forget every compiled function (``torch.compiler.reset()``): a runner whose compiled
    functions were built before must build them again, with their guards checked
    (``cpg_actor.training.compile_stance``)."""
    return _compiles_forgotten


def compile_reproducibly(fn, **options):
    """``torch.compile(fn)`` as this project compiles (the loss, the policy step, the reward
    normaliser): kernels specialised per shape (``dynamic=False``: the same whatever shapes
    came before, so a resumed run computes what an uninterrupted one does), and no masked
    vector loads in loop tails: they let stray lanes into reductions, and results varied in
    the last bits from run to run. ``options``: more inductor options."""
    return torch.compile(fn, dynamic=False, options={"cpp.enable_loop_tail_vec": False, **options})


class PPO:
    def __init__(self, agent: Agent, config: PPOConfig) -> None:
        self.agent = agent
        self.config = config
        self.learning_rate = config.learning_rate
        # fused: one kernel per step for all parameters instead of a Python loop over them
        groups: list[dict] = [{"params": list(agent.parameters())}]
        cpg = agent.cpg_parameters() if config.cpg_learning_rate is not None else []
        if cpg:  # the CPG's own group, at its own rate (ppo.cpg_lr_schedule)
            ids = {id(p) for p in cpg}
            groups = [
                {"params": [p for p in agent.parameters() if id(p) not in ids]},
                {"params": cpg, "lr": config.cpg_learning_rate, "fixed_lr": True},
            ]
        self.optimizer = torch.optim.Adam(
            groups, lr=config.learning_rate, eps=config.adam_eps, fused=True
        )
        self._clipped = list(agent.parameters())  # clip_grad_norm_'s order: the agent's
        # torch.compile fuses the loss's small operators (forward and backward) into a few
        # kernels, after a one-off compile: small minibatches are dominated by their overhead
        if config.compile and not cpp_compiler():
            raise ValueError(
                "ppo.compile=true needs a C++ compiler for torch.compile's CPU backend and none "
                "was found (g++, c++, clang++); install one (e.g. apt install g++) or pass "
                "--set ppo.compile=false"
            )
        self.loss = ppo_loss
        self.outputs_are_finite = outputs_are_finite
        if config.compile:
            # a fresh compile for every run: dynamo caches per function, and a process that
            # builds many runs (tests, sweeps) would otherwise pile up recompilations
            forget_compiled()
            self.loss = compile_reproducibly(ppo_loss)
            # the check after every update: one fused pass instead of the eager actor and
            # critic over the whole rollout
            self.outputs_are_finite = compile_reproducibly(outputs_are_finite)
        # the loss, its gradient, the clip and the Adam step as one compiled function, where it
        # computes what the separate calls compute (train_step.usable): less overhead per step
        # at the paper's 64-sample minibatches
        self.fused_step = (
            train_step.make(agent, self.optimizer, config, ppo_loss, compile_reproducibly)
            if config.compile and config.fused_step
            else None
        )

    def set_learning_rate(self, lr: float) -> None:
        self.learning_rate = lr
        for group in self.optimizer.param_groups:
            if not group.get("fixed_lr", False):
                group["lr"] = lr
            elif self.config.cpg_lr_schedule != "fixed":
                group["lr"] = cpg_learning_rate(lr, self.config)

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

    def _outputs_are_finite(self, storage: RolloutStorage) -> bool:
        """The updated policy's mean, std and value on every stored (observation, state)."""
        # flattened in order: no random permutation, so training's RNG stream is untouched
        obs, states = (getattr(storage, name).flatten(0, 1) for name in ("observations", "states"))
        return bool(self.outputs_are_finite(self.agent, obs, states))

    def update(self, storage: RolloutStorage) -> dict[str, float]:
        cfg = self.config
        history: list[Tensor] = []  # one row of the six statistics per minibatch
        early_stop = False
        # a finite loss with a huge step can still break the policy: every update is checked
        # (loss and gradient norm at each step, parameters and outputs at the end) and undone
        # if it did, so nothing non-finite is ever used, logged or saved
        snapshot = [p.detach().clone() for p in self._parameters()]
        for _ in range(cfg.num_epochs):
            for batch in storage.minibatches(cfg.num_minibatches, cfg.bptt_steps):
                if self.fused_step is not None:  # the step below, Adam included, in one call
                    loss, grad_norm, stats = self.fused_step(batch)
                    if cfg.lr_schedule == "adaptive":  # the rate the step chose and used
                        self.set_learning_rate(self.fused_step.learning_rate)
                else:
                    loss, stats = self.loss(self.agent, batch, cfg)
                    if cfg.lr_schedule == "adaptive":
                        rate = torch.tensor(self.learning_rate, dtype=torch.float64)
                        kl = stats[5].detach().cpu()
                        self.set_learning_rate(adaptive_learning_rate(kl, rate, cfg).item())
                    for p in self._clipped:  # optimizer.zero_grad(set_to_none=True), leaner
                        p.grad = None
                    loss.backward()
                    grad_norm = clip_grad_norm_(self._clipped, cfg.max_grad_norm)
                # one host sync per step: a non-finite loss gives a non-finite gradient norm
                if not torch.isfinite(loss + grad_norm):
                    values = ", ".join(
                        f"{k} {v:g}" for k, v in zip(STATS, stats.tolist(), strict=True)
                    )
                    raise self._undo(
                        snapshot,
                        f"non-finite PPO loss or gradient ({values}, "
                        f"gradient norm {grad_norm.item():g})",
                    )
                if self.fused_step is None:
                    adam_step(self.optimizer)
                history.append(stats)
                if cfg.target_kl is not None and stats[3].item() > cfg.target_kl:
                    early_stop = True
                    break
            if early_stop:
                break

        if not all(bool(torch.isfinite(p).all()) for p in self._parameters()):
            raise self._undo(snapshot, "an optimiser step made the parameters non-finite")
        if not self._outputs_are_finite(storage):
            raise self._undo(snapshot, "the updated policy gives non-finite actions or values")
        values = storage.values.flatten()
        returns = storage.returns.flatten()
        var_returns = returns.var().item()
        explained = (
            math.nan if var_returns == 0 else 1.0 - (returns - values).var().item() / var_returns
        )
        means = torch.stack(history).mean(0).tolist() if history else []
        result = dict(zip(STATS, means, strict=False))
        result.update(
            explained_variance=explained,
            learning_rate=self.learning_rate,
            early_stop=float(early_stop),
            num_minibatch_updates=float(len(history)),
        )
        for group in self.optimizer.param_groups:
            if group.get("fixed_lr", False):  # ppo.cpg_learning_rate's group
                result["cpg_learning_rate"] = group["lr"]
        return result
