"""Torch threads of the PPO update, which runs while the simulator's threads are idle."""

from __future__ import annotations

from cpg_actor.config import TrainConfig
from cpg_actor.machine import usable_cores


def update_threads(config: TrainConfig) -> int:
    """``config.update_threads`` where set; else every usable core for minibatches of at least
    1024 samples (large enough to gain from them), the rollout's ``torch_threads`` otherwise."""
    if config.update_threads is not None:
        return config.update_threads
    minibatch = config.steps_per_iteration // config.ppo.num_minibatches
    return usable_cores() if minibatch >= 1024 else config.torch_threads
