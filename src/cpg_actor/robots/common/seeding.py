"""The seed of every env of a batch, from a vector env's ``reset(seed=...)``."""

from __future__ import annotations

from typing import Any

import numpy as np


def env_seeds(seed: Any, num_envs: int) -> list[int]:
    """The seed of every env from a vector env's ``reset(seed=...)``: an int s gives env i
    ``s + i`` (Gymnasium's convention), a list gives one per env; ValueError otherwise."""
    if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
        return [int(seed) + i for i in range(num_envs)]
    if isinstance(seed, (list, tuple)) and len(seed) == num_envs:
        return [int(s) for s in seed]
    raise ValueError(f"seed must be an int or a list of {num_envs} ints, got {seed!r}")
