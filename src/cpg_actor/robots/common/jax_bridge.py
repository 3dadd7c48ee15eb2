"""Between a robot's MJX env and torch: JAX random keys from Gymnasium seeds, the torch
device of a JAX device, and results copied to the host as numpy (never views of JAX's
buffers). Imported only where an MJX env is asked for."""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from cpg_actor.robots.common.mjx_runtime import load
from cpg_actor.robots.common.seeding import env_seeds

jax, _ = load()


def reset_keys(seed: int | list[int] | None, num_envs: int, device) -> Any:
    """The JAX keys ``(N, 2)`` on ``device`` of a vector env's ``reset(seed=...)``: an int s
    gives env i the seed s + i, a list one per env, None fresh entropy; ValueError for a
    negative seed."""
    if seed is None:
        seeds = [int(s) for s in np.random.SeedSequence().generate_state(num_envs)]
    else:
        seeds = env_seeds(seed, num_envs)
    if any(s < 0 for s in seeds):
        raise ValueError(f"seeds must be >= 0, got {seed!r}")
    return jax.device_put(seed_keys(seeds), device)


def seed_keys(seeds: list[int]) -> np.ndarray:
    """One JAX random key (raw threefry ``uint32[2]``) per env from integer seeds of any size,
    through numpy's ``SeedSequence``: ``(N, 2)`` uint32."""
    return np.stack([np.random.SeedSequence(s).generate_state(2, dtype=np.uint32) for s in seeds])


def torch_device(jax_device) -> torch.device:
    """The torch device of a JAX device (``cuda:i`` for JAX's GPU i, else the CPU)."""
    if jax_device.platform in ("gpu", "cuda"):
        return torch.device("cuda", jax_device.id)
    return torch.device("cpu")


def to_host(value: Any) -> Any:
    """Tensors (and dicts of them) as numpy arrays on the host (copies: never views of JAX's
    buffers)."""
    if isinstance(value, dict):
        return {k: to_host(v) for k, v in value.items()}
    if isinstance(value, torch.Tensor):
        return value.cpu().numpy().copy()
    return value
