"""The seeds of a training run: everything random derives from ``TrainConfig.seed``."""

from __future__ import annotations

import random

import numpy as np
import torch

WARM_START_SEED_KEY = 2**31  # derived_seed(seed, this) seeds the warm start's environments
EVAL_SEED_KEY = 2**31 + 1  # derived_seed(seed, this) resets the evaluation envs, every time


def derived_seed(seed: int, iteration: int) -> int:
    """The environments' reset seed after ``iteration`` iterations of a run seeded ``seed``."""
    return int(np.random.SeedSequence([seed, iteration]).generate_state(1)[0])


def seed_everything(seed: int) -> None:
    """Seed torch (action noise, minibatch order, initialisation), numpy and python."""
    random.seed(seed)
    np.random.seed(seed % 2**32)  # noqa: NPY002 (third-party code may use the global RNG)
    torch.manual_seed(seed)
