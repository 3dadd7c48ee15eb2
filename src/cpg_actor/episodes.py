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

from cpg_actor.envs.torch_env import EnvStep

WINDOW = 100  # finished episodes averaged in the logs


@dataclass
class EpisodeStats:
    """Per-environment accumulators of the episode in progress."""

    returns: np.ndarray
    lengths: np.ndarray
    terms: dict[str, np.ndarray]

    @classmethod
    def zeros(cls, num_envs: int) -> EpisodeStats:
        return cls(np.zeros(num_envs), np.zeros(num_envs, dtype=np.int64), {})

    def state_dict(self) -> dict[str, Any]:
        arrays = {"returns": self.returns, "lengths": self.lengths}
        return {
            **{k: torch.from_numpy(v.copy()) for k, v in arrays.items()},
            "terms": {k: torch.from_numpy(v.copy()) for k, v in self.terms.items()},
        }

    @classmethod
    def from_state_dict(cls, state: dict[str, Any]) -> EpisodeStats:
        return cls(
            state["returns"].numpy().copy(),
            state["lengths"].numpy().copy(),
            {k: v.numpy().copy() for k, v in state["terms"].items()},
        )


class EpisodeLog:
    """The episodes in progress (``running``) and the last :data:`WINDOW` values of each
    quantity of the finished ones (``recent``: ``return``, ``length``, ``charts/<metric>``,
    ``reward_terms/<term>``)."""

    def __init__(self, num_envs: int) -> None:
        self.running = EpisodeStats.zeros(num_envs)
        self.recent: dict[str, deque] = {}

    def track(self, out: EnvStep, done: torch.Tensor) -> None:
        """Add one env step; close the episodes that ``done`` marks."""
        ep = self.running
        ep.returns += out.reward.cpu().numpy().astype(np.float64)
        ep.lengths += 1
        for name, value in out.reward_terms.items():
            ep.terms.setdefault(name, np.zeros_like(ep.returns))
            ep.terms[name] += value.cpu().numpy()
        done = done.cpu().numpy()
        if not done.any():
            return
        metrics = {name: values.cpu().numpy() for name, values in out.episode_metrics.items()}
        for i in np.flatnonzero(done):
            self.remember("return", ep.returns[i])
            self.remember("length", ep.lengths[i])
            for name, values in metrics.items():
                if np.isfinite(values[i]):
                    self.remember(f"charts/{name}", values[i])  # logged under this name
            for name, value in ep.terms.items():
                self.remember(f"reward_terms/{name}", value[i])
        ep.returns[done] = 0.0
        ep.lengths[done] = 0
        for value in ep.terms.values():
            value[done] = 0.0

    def remember(self, key: str, value: float) -> None:
        self.recent.setdefault(key, deque(maxlen=WINDOW)).append(float(value))

    def mean(self, key: str) -> float:
        """Mean over the recent finished episodes; NaN before the first one."""
        values = self.recent.get(key)
        return float(np.mean(values)) if values else math.nan

    def env_metrics(self) -> dict[str, float]:
        """The env's episode metrics (e.g. ``hop_height``), each a mean over recent episodes."""
        return {
            key.removeprefix("charts/"): self.mean(key)
            for key in sorted(self.recent)
            if key.startswith("charts/")
        }

    def scalars(self) -> dict[str, float]:
        """The logged episode scalars: return, length, the env's metrics, the reward terms."""
        row = {"charts/episode_return": self.mean("return")}
        row["charts/episode_length"] = self.mean("length")
        for key in sorted(self.recent):
            if key.startswith(("charts/", "reward_terms/")):
                row[key] = self.mean(key)
        return row

    def recent_state(self) -> dict[str, list[float]]:
        return {key: list(values) for key, values in self.recent.items()}

    def load_recent(self, state: dict[str, list[float]]) -> None:
        self.recent = {key: deque(values, maxlen=WINDOW) for key, values in state.items()}
