"""One PPO gradient step as one compiled function: loss, gradient, clip and Adam together.

At the paper's settings the update makes 320 gradient steps of 64 samples per 2,048 samples,
and each step's cost is mostly overhead around small kernels: the autograd engine running the
compiled backward, then the clip and the Adam step as separate calls. :class:`FusedTrainStep`
compiles the whole step, ``torch.func.grad`` of the PPO loss (:func:`ppo_loss`) through
``functional_call``, the global-norm clip, the adaptive learning-rate rule (``lr_schedule=
"adaptive"``: the step's KL sets the rate before its Adam update, as ``PPO.update`` does) and
the Adam update, into one ``torch.compile``d function that writes the new parameters, the Adam
moments and the rate in place, so the overhead between the kernels goes.

It computes the same algorithm with the same Adam state (``optimizer.state``: ``step``,
``exp_avg``, ``exp_avg_sq``, so checkpoints and resume are unchanged), but not the same bits
as the separate calls: the compiler fuses and orders the floating-point operations its own way.
Adam follows the formula of torch's fused kernel: ``m = b1 m + (1 - b1) g``, ``v = b2 v + (1 -
b2) g^2``, ``p -= lr / (1 - b1^t) * m / (sqrt(v) / sqrt(1 - b2^t) + eps)``, with the gradient
scaled by ``min(1, max_norm / (||g|| + 1e-6))`` first, as ``clip_grad_norm_``.
"""

from __future__ import annotations

from typing import Any

import torch
from torch import Tensor, nn
from torch.func import functional_call, grad

from cpg_actor.ppo.config import PPOConfig
from cpg_actor.ppo.optimizer import adaptive_learning_rate, cpg_learning_rate


class _Loss(nn.Module):
    """The PPO loss of the agent as a module's forward (for ``functional_call``)."""

    def __init__(self, agent: nn.Module, config: PPOConfig, loss) -> None:
        super().__init__()
        self.agent = agent
        self.config = config
        self.loss = loss

    def forward(self, batch: dict[str, Tensor]) -> tuple[Tensor, Tensor]:
        return self.loss(self.agent, batch, self.config)


def usable(optimizer: torch.optim.Optimizer) -> bool:
    """Whether :class:`FusedTrainStep` computes what the update's separate calls compute: a
    plain Adam (no weight decay, amsgrad or maximize) over parameters on the CPU in float32."""
    if not isinstance(optimizer, torch.optim.Adam):
        return False
    for group in optimizer.param_groups:
        if group["amsgrad"] or group["maximize"] or group["weight_decay"]:
            return False
        for p in group["params"]:
            if p.device.type != "cpu" or p.dtype != torch.float32:
                return False
    return True


class FusedTrainStep:
    """``step(batch) -> (loss, grad_norm, stats)``: one PPO gradient step of ``agent`` with
    ``optimizer``'s Adam settings and state, compiled (module docstring). The parameters and
    the optimizer's state are updated in place; ``stats`` are :func:`ppo_loss`'s."""

    def __init__(self, agent: nn.Module, optimizer: torch.optim.Adam, config: PPOConfig, loss,
                 compile_fn) -> None:  # fmt: skip
        self.optimizer = optimizer
        self.module = _Loss(agent, config, loss)
        by_id = {id(p): name for name, p in self.module.named_parameters()}
        self.names: list[str] = []
        self.params: list[Tensor] = []
        self.group_of: list[int] = []
        for g, group in enumerate(optimizer.param_groups):
            for p in group["params"]:
                self.names.append(by_id[id(p)])
                self.params.append(p)
                self.group_of.append(g)
        self.betas = [tuple(group["betas"]) for group in optimizer.param_groups]
        self.eps = [float(group["eps"]) for group in optimizer.param_groups]
        self.max_norm = float(config.max_grad_norm)
        # the adaptive rule (rsl_rl) in the step: its KL sets the rate of the groups without
        # a fixed one before their Adam step, as PPO.update does with the separate calls
        self.adaptive = config.lr_schedule == "adaptive"
        self.scheduled = [
            g for g, group in enumerate(optimizer.param_groups) if not group.get("fixed_lr")
        ]
        # the CPG's group when its rate follows the others' (ppo.cpg_lr_schedule="follow")
        self.following = [
            g
            for g, group in enumerate(optimizer.param_groups)
            if group.get("fixed_lr") and config.cpg_lr_schedule == "follow"
        ]
        self.config = config
        self._lr = torch.zeros(len(optimizer.param_groups), dtype=torch.float64)
        self.learning_rate = float(optimizer.param_groups[self.scheduled[0]]["lr"])
        self._compiled = compile_fn(self._step)

    def _state(self) -> list[dict[str, Tensor]]:
        """The optimizer's state of each parameter, made as torch's fused Adam makes it."""
        states = []
        for p in self.params:
            state = self.optimizer.state[p]
            if not state:
                state["step"] = torch.tensor(0.0, dtype=torch.float32, device=p.device)
                state["exp_avg"] = torch.zeros_like(p, memory_format=torch.preserve_format)
                state["exp_avg_sq"] = torch.zeros_like(p, memory_format=torch.preserve_format)
            states.append(state)
        return states

    def _step(self, data, exp_avgs, exp_avg_sqs, steps, lr, batch):
        names = self.names

        def loss_of(values):
            loss, stats = functional_call(self.module, dict(zip(names, values, strict=True)),
                                          (batch,))  # fmt: skip
            return loss, (loss, stats)

        grads, (loss, stats) = grad(loss_of, has_aux=True)(list(data))
        if self.adaptive:  # PPO.update's rule, the same function
            rate = adaptive_learning_rate(stats[5], lr[self.scheduled[0]], self.config)
            for group in self.scheduled:
                lr[group].copy_(rate)
            for group in self.following:
                lr[group].copy_(cpg_learning_rate(rate, self.config))
        norms = torch.stack([torch.linalg.vector_norm(g, 2.0) for g in grads])
        total_norm = torch.linalg.vector_norm(norms, 2.0)
        scale = torch.clamp(self.max_norm / (total_norm + 1e-6), max=1.0)
        for i, (p, g, m, v, t) in enumerate(
            zip(data, grads, exp_avgs, exp_avg_sqs, steps, strict=True)
        ):
            group = self.group_of[i]
            beta1, beta2 = self.betas[group]
            g = g * scale
            t.add_(1.0)
            m.mul_(beta1).add_(g, alpha=1.0 - beta1)
            v.mul_(beta2).addcmul_(g, g, value=1.0 - beta2)
            step_size = lr[group] / (1.0 - beta1**t)
            denom = v.sqrt() / torch.sqrt(1.0 - beta2**t) + self.eps[group]
            p.sub_(step_size * m / denom)
        return loss, total_norm, stats

    def __call__(self, batch: dict[str, Tensor]) -> tuple[Tensor, Tensor, Tensor]:
        states = self._state()
        for g, group in enumerate(self.optimizer.param_groups):
            self._lr[g] = group["lr"]
        data = [p.detach() for p in self.params]
        out = self._compiled(
            data,
            [s["exp_avg"] for s in states],
            [s["exp_avg_sq"] for s in states],
            [s["step"] for s in states],
            self._lr,
            batch,
        )
        if self.adaptive:  # the rate the step chose; PPO.set_learning_rate puts it in the groups
            self.learning_rate = self._lr[self.scheduled[0]].item()
        return out


def make(agent: nn.Module, optimizer: Any, config: PPOConfig, loss, compile_fn):
    """A :class:`FusedTrainStep` where :func:`usable`, else None."""
    if not usable(optimizer):
        return None
    return FusedTrainStep(agent, optimizer, config, loss, compile_fn)
