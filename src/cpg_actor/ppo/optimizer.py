"""The gradient clip and the Adam step of a PPO minibatch, without torch's per-call Python.

At the paper's settings (320 gradient steps of 64 samples per 2,048 samples) the update makes
thousands of small steps, and ``torch.nn.utils.clip_grad_norm_`` and ``torch.optim.Adam.step``
spend most of their time in Python around a few kernels (grouping the tensors by device,
checks, profiler hooks), a large share of the update for a network of few small tensors.
These functions call the same kernels in the same
order with the same arguments, so the results are the same bit for bit
(``tests/ppo/test_optimizer.py``); where that cannot be promised (tensors on several devices
or of several dtypes, an Adam that is not the fused one or whose state does not exist yet) they
call torch's own.
"""

from __future__ import annotations

import torch
from torch import Tensor


def adaptive_learning_rate(kl: Tensor, rate: Tensor, config) -> Tensor:
    """The learning rate after a minibatch of KL ``kl`` (``lr_schedule="adaptive"``, rsl_rl):
    ``rate / 1.5`` (at least ``min_learning_rate``) when KL > 2 ``desired_kl``, ``rate x 1.5``
    (at most ``max_learning_rate``) when 0 < KL < ``desired_kl`` / 2, else ``rate``. In float64
    (``rate`` a float64 tensor): the same numbers as Python floats. Pure tensor code, so the
    fused step (``ppo/train_step.py``) computes it inside its compiled function."""
    kl = kl.to(torch.float64)
    low, high = float(config.min_learning_rate), float(config.max_learning_rate)
    desired = float(config.desired_kl)
    return torch.where(
        kl > 2.0 * desired,
        torch.clamp(rate / 1.5, min=low),
        torch.where((kl > 0.0) & (kl < 0.5 * desired), torch.clamp(rate * 1.5, max=high), rate),
    )


def cpg_learning_rate(rate, config):
    """The CPG group's rate when the others' is ``rate`` (``ppo.cpg_lr_schedule``): its own
    ``cpg_learning_rate`` ("fixed"), or that times ``min(1, rate / learning_rate)``
    ("follow"). ``rate`` a float or a float64 tensor (the fused step's)."""
    base = float(config.cpg_learning_rate)
    if config.cpg_lr_schedule == "fixed":
        return base
    ratio = rate / float(config.learning_rate)
    if isinstance(ratio, Tensor):
        return base * torch.clamp(ratio, max=1.0)
    return base * min(1.0, ratio)


def _uniform(tensors: list[Tensor]) -> bool:
    """One device and one dtype: torch's functions then make a single group, in this order."""
    first = tensors[0]
    return all(t.device == first.device and t.dtype == first.dtype for t in tensors)


def clip_grad_norm_(parameters: list[Tensor], max_norm: float) -> Tensor:
    """``torch.nn.utils.clip_grad_norm_(parameters, max_norm, foreach=True)``: scale the
    gradients so that their joint 2-norm is at most ``max_norm``; the norm before scaling."""
    grads = [p.grad for p in parameters if p.grad is not None]
    if not grads or not _uniform(grads):
        return torch.nn.utils.clip_grad_norm_(parameters, max_norm, foreach=True)
    total_norm = torch.linalg.vector_norm(torch.stack(torch._foreach_norm(grads, 2.0)), 2.0)
    torch._foreach_mul_(grads, torch.clamp(max_norm / (total_norm + 1e-6), max=1.0))
    return total_norm


def adam_step(optimizer: torch.optim.Adam) -> None:
    """``optimizer.step()`` for a fused Adam (``fused=True``, no weight decay, amsgrad or
    maximize) whose state exists; anything else goes to ``optimizer.step()`` itself."""
    plans = []
    for group in optimizer.param_groups:
        params = [p for p in group["params"] if p.grad is not None]
        states = [optimizer.state.get(p) for p in params]
        lean = (
            group.get("fused")
            and not (group["amsgrad"] or group["maximize"] or group["weight_decay"])
            and not any(
                group.get(k) for k in ("capturable", "differentiable", "decoupled_weight_decay")
            )
            and params
            and all(state for state in states)
            and _uniform(params)
        )
        if not lean:
            if params:
                optimizer.step()
                return
            continue
        plans.append((group, params, states))
    for group, params, states in plans:
        steps = [state["step"] for state in states]
        beta1, beta2 = group["betas"]
        torch._foreach_add_(steps, 1)
        torch._fused_adam_(
            params, [p.grad for p in params], [state["exp_avg"] for state in states],
            [state["exp_avg_sq"] for state in states], [], steps, amsgrad=False,
            lr=group["lr"], beta1=beta1, beta2=beta2, weight_decay=0.0, eps=group["eps"],
            maximize=False, grad_scale=None, found_inf=None,
        )  # fmt: skip
