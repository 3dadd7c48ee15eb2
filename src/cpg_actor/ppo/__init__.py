"""PPO written out: rollout storage with the CPG state, GAE, running normalisation, update."""

from cpg_actor.ppo.algorithm import (
    PPO,
    NonFiniteLossError,
    compile_generation,
    compile_reproducibly,
    gaussian_kl,
)
from cpg_actor.ppo.config import PPOConfig
from cpg_actor.ppo.normalizer import RewardNormalizer, RunningNormalizer
from cpg_actor.ppo.storage import RolloutStorage, compute_gae

__all__ = [
    "PPO",
    "NonFiniteLossError",
    "PPOConfig",
    "RewardNormalizer",
    "RolloutStorage",
    "RunningNormalizer",
    "compile_generation",
    "compile_reproducibly",
    "compute_gae",
    "gaussian_kl",
]
