"""Running observation normalisation (mean and variance over everything seen so far)."""

from __future__ import annotations

import torch
from torch import Tensor, nn


class RunningNormalizer(nn.Module):
    """``(x - mean) / sqrt(var + eps)``, clipped to ``+-clip``, with running statistics.

    Statistics are merged batch by batch with the parallel algorithm of Chan et al. (exact for
    the population mean and variance of all samples seen). They are buffers, so they are part
    of ``state_dict()`` and travel with checkpoints. :meth:`update` is called by the runner
    during rollouts only; the PPO update never touches it (the stored observations are already
    normalised), so the normaliser is frozen while gradients are computed.
    """

    def __init__(self, size: int, epsilon: float = 1e-8, clip: float = 10.0) -> None:
        super().__init__()
        self.epsilon = epsilon
        self.clip = clip
        self.register_buffer("mean", torch.zeros(size, dtype=torch.float64))
        self.register_buffer("var", torch.ones(size, dtype=torch.float64))
        self.register_buffer("count", torch.zeros((), dtype=torch.float64))

    @torch.no_grad()
    def update(self, x: Tensor) -> None:
        """Merge a batch ``(B, size)`` into the running statistics."""
        x = x.to(torch.float64).reshape(-1, self.mean.shape[0])
        batch_count = x.shape[0]
        if batch_count == 0:
            return
        batch_var, batch_mean = torch.var_mean(x, dim=0, correction=0)
        count = self.count
        total = count + batch_count
        weight = batch_count / total  # the batch's share of all samples
        delta = batch_mean - self.mean
        # M2 / total = var (1 - w) + batch_var w + delta^2 w (1 - w), w = the batch's share
        self.var.mul_(1.0 - weight).add_(
            batch_var * weight + delta.square() * (weight * (1.0 - weight))
        )
        self.mean.add_(delta * weight)
        # not count.copy_(total): under torch.compile (2.13, CPU) an in-place op on a 0-dim
        # buffer is dropped, and the count would stay 0; an indexed write is kept
        self.count[...] = total

    def forward(self, x: Tensor) -> Tensor:
        """Normalise ``x`` (any leading shape); does not update the statistics."""
        return self._normalized(x, self.mean, self.var)

    def leading(self, x: Tensor) -> Tensor:
        """Normalise ``x``, the first ``x.shape[-1]`` entries of an observation (an actor's
        without the critic's privileged entries), as :meth:`forward` does in the whole."""
        size = x.shape[-1]
        return self._normalized(x, self.mean[:size], self.var[:size])

    def _normalized(self, x: Tensor, mean: Tensor, var: Tensor) -> Tensor:
        std = torch.sqrt(var + self.epsilon)
        y = (x.to(torch.float64) - mean) / std
        return y.clamp(-self.clip, self.clip).to(x.dtype)


class RewardNormalizer(nn.Module):
    """VecNormalize-style reward scaling (OpenAI Baselines, ``vec_normalize.py``).

    Each environment keeps its discounted return ``G <- gamma G + r`` (reset to 0 when its
    episode ends); the running variance of every ``G`` seen so far scales the reward:
    ``r / sqrt(var(G) + eps)``, clipped to ``+-clip``. The mean is not subtracted, so the sign
    of a reward is kept. Used on the training rewards only (logged returns stay raw). The
    statistics are buffers and travel with checkpoints; the per-env returns (``discounted``)
    travel with the episodes in progress (``cpg_actor.training.rollout.Rollout.state``) and
    are reset with new episodes (:meth:`reset`).
    """

    def __init__(
        self, num_envs: int, gamma: float, epsilon: float = 1e-8, clip: float = 10.0
    ) -> None:
        super().__init__()
        self.gamma = gamma
        self.epsilon = epsilon
        self.clip = clip
        self.returns_rms = RunningNormalizer(1)
        # a buffer (moves with .to(device)) but not in state_dict: it belongs to the episodes
        # in progress, which the runner saves on their own
        self.register_buffer("discounted", torch.zeros(num_envs, dtype=torch.float64), False)

    def reset(self) -> None:
        self.discounted.zero_()

    @torch.no_grad()
    def forward(self, reward: Tensor, done: Tensor) -> Tensor:
        """Scale a step's rewards ``(N,)``; ``done`` ``(N,)`` marks episodes that just ended."""
        self.discounted.mul_(self.gamma).add_(reward.to(torch.float64))
        self.returns_rms.update(self.discounted.unsqueeze(-1))
        std = torch.sqrt(self.returns_rms.var[0] + self.epsilon)
        scaled = (reward.to(torch.float64) / std).clamp(-self.clip, self.clip)
        self.discounted.masked_fill_(done.to(torch.bool), 0.0)
        return scaled.to(reward.dtype)
