"""Episode bookkeeping of a training run: what the episodes in progress have accumulated, and
the values of the last finished ones (returns, lengths, reward terms, the env's own episode
metrics) that the logs and the progress display average."""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch

from cpg_actor.robots.common.torch_env import EnvStep

WINDOW = 100  # finished episodes averaged in the logs


@dataclass
class EpisodeStats:
    """Per-environment accumulators of the episode in progress, tensors on the env's device
    (on a GPU they stay there: only the finished episodes' values go to the host)."""

    returns: torch.Tensor  # (N,) float64
    lengths: torch.Tensor  # (N,) int64
    terms: dict[str, torch.Tensor]  # (N,) float64 each

    @classmethod
    def zeros(cls, num_envs: int, device: torch.device | str = "cpu") -> EpisodeStats:
        return cls(
            torch.zeros(num_envs, dtype=torch.float64, device=device),
            torch.zeros(num_envs, dtype=torch.int64, device=device),
            {},
        )

    def state_dict(self) -> dict[str, Any]:
        return {
            "returns": self.returns.cpu().clone(),
            "lengths": self.lengths.cpu().clone(),
            "terms": {k: v.cpu().clone() for k, v in self.terms.items()},
        }

    @classmethod
    def from_state_dict(
        cls, state: dict[str, Any], device: torch.device | str = "cpu"
    ) -> EpisodeStats:
        return cls(
            state["returns"].to(device, torch.float64).clone(),
            state["lengths"].to(device, torch.int64).clone(),
            {k: v.to(device, torch.float64).clone() for k, v in state["terms"].items()},
        )


class EpisodeLog:
    """The episodes in progress (``running``) and the last :data:`WINDOW` values of each
    quantity of the finished ones (``recent``: ``return``, ``length``, ``charts/<metric>``,
    ``reward_terms/<term>``).

    ``deferred``: :meth:`track` never waits for the device (no "did an episode end?" per
    step); the finished episodes' values wait on the device until :meth:`flush`, which the
    trainer calls once per rollout and every reader calls first. Same values, same order."""

    MAX_PENDING = 1024  # deferred steps kept on the device before a flush is forced

    def __init__(self, num_envs: int, deferred: bool = False) -> None:
        self.running = EpisodeStats.zeros(num_envs)
        self.recent: dict[str, deque] = {}
        self.deferred = deferred
        # deferred steps: (done (N,), values (N, K)), the column names of the values
        self._pending: list[tuple[torch.Tensor, torch.Tensor]] = []
        self._pending_keys: tuple[str, ...] = ()

    def track(self, out: EnvStep, done: torch.Tensor) -> None:
        """Add one env step; close the episodes that ``done`` marks. On the device until an
        episode ends (deferred: until :meth:`flush`); then one copy of the finished episodes'
        values to the host."""
        ep = self.running
        device = ep.returns.device
        ep.returns += out.reward.to(device, torch.float64)
        ep.lengths += 1
        for name, value in out.reward_terms.items():
            if name not in ep.terms:
                ep.terms[name] = torch.zeros_like(ep.returns)
            ep.terms[name] += value.to(device, torch.float64)
        done = done.to(device)
        if self.deferred:
            columns = self._columns(out, device)
            keys = tuple(columns)
            if self._pending and keys != self._pending_keys:  # a new column: flush the old
                self.flush()
            self._pending_keys = keys
            self._pending.append((done, torch.stack(list(columns.values()), dim=1)))
            self._restart(done)
            if len(self._pending) >= self.MAX_PENDING:
                self.flush()
            return
        if not bool(done.any()):
            return
        rows = done.nonzero().squeeze(-1)
        columns = self._columns(out, device)
        # every finished value in one (k, columns) float64 tensor: one copy to the host
        finished = torch.stack([v[rows] for v in columns.values()], dim=1).cpu().numpy()
        self._remember_rows(tuple(columns), finished)
        self._restart(done)

    def flush(self) -> None:
        """Move the deferred steps' finished episodes to ``recent`` (one copy to the host)."""
        if not self._pending:
            return
        done = torch.stack([d for d, _ in self._pending])  # (T, N)
        values = torch.stack([v for _, v in self._pending])  # (T, N, K)
        self._pending = []
        # step by step, env by env: the order of the per-step path
        self._remember_rows(self._pending_keys, values[done].cpu().numpy())

    def _columns(self, out: EnvStep, device: torch.device) -> dict[str, torch.Tensor]:
        """Every env's episode values this step, (N,) float64 each, by their names."""
        ep = self.running
        columns = {"return": ep.returns, "length": ep.lengths.to(torch.float64)}
        for name, values in out.episode_metrics.items():
            columns[f"charts/{name}"] = values.to(device, torch.float64)  # logged under this name
        for name, value in ep.terms.items():
            columns[f"reward_terms/{name}"] = value
        return columns

    def _remember_rows(self, keys: tuple[str, ...], finished: np.ndarray) -> None:
        for row in finished:
            for key, value in zip(keys, row, strict=True):
                if key.startswith("charts/") and not np.isfinite(value):
                    continue
                self.remember(key, value)

    def _restart(self, done: torch.Tensor) -> None:
        """Zero the accumulators of the episodes that ended (on the device, no wait)."""
        ep = self.running
        ep.returns.masked_fill_(done, 0.0)
        ep.lengths.masked_fill_(done, 0)
        for value in ep.terms.values():
            value.masked_fill_(done, 0.0)

    def remember(self, key: str, value: float) -> None:
        self.recent.setdefault(key, deque(maxlen=WINDOW)).append(float(value))

    def mean(self, key: str) -> float:
        """Mean over the recent finished episodes; NaN before the first one."""
        self.flush()
        values = self.recent.get(key)
        return float(np.mean(values)) if values else math.nan

    def env_metrics(self) -> dict[str, float]:
        """The env's episode metrics (e.g. ``hop_height``), each a mean over recent episodes."""
        self.flush()
        return {
            key.removeprefix("charts/"): self.mean(key)
            for key in sorted(self.recent)
            if key.startswith("charts/")
        }

    def scalars(self) -> dict[str, float]:
        """The logged episode scalars: return, length, the env's metrics, the reward terms."""
        self.flush()
        row = {"charts/episode_return": self.mean("return")}
        row["charts/episode_length"] = self.mean("length")
        for key in sorted(self.recent):
            if key.startswith(("charts/", "reward_terms/")):
                row[key] = self.mean(key)
        return row

    def recent_state(self) -> dict[str, list[float]]:
        self.flush()
        return {key: list(values) for key, values in self.recent.items()}

    def load_recent(self, state: dict[str, list[float]]) -> None:
        self._pending = []
        self.recent = {key: deque(values, maxlen=WINDOW) for key, values in state.items()}
