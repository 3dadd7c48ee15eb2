"""Every number of the PPO algorithm, in one dataclass."""

from __future__ import annotations

from dataclasses import dataclass

SCHEDULES = ("fixed", "linear", "adaptive")


@dataclass
class PPOConfig:
    """PPO hyper-parameters (defaults: CleanRL's continuous-control PPO; rsl_rl's KL rule optional).

    One iteration collects ``num_steps`` control steps in each of the runner's environments,
    then runs ``num_epochs`` passes over that batch in ``num_minibatches`` minibatches.
    """

    num_steps: int = 32  # control steps per environment per iteration (rollout length)
    num_epochs: int = 5
    num_minibatches: int = 4
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_ratio: float = 0.2  # epsilon of the clipped surrogate
    clip_value_loss: bool = True
    value_loss_coef: float = 0.5
    entropy_coef: float = 0.0
    normalize_advantages: bool = True  # per minibatch
    max_grad_norm: float = 1.0
    learning_rate: float = 3e-4
    lr_schedule: str = "fixed"  # fixed | linear (to 0 at the last iteration) | adaptive (KL)
    desired_kl: float = 0.01  # adaptive schedule: lr /1.5 above 2x, *1.5 below 0.5x
    min_learning_rate: float = 1e-5
    max_learning_rate: float = 1e-2
    target_kl: float | None = None  # stop the epochs of an iteration once approx_kl exceeds it
    adam_eps: float = 1e-5
    normalize_observations: bool = True

    def validate(self) -> None:
        positive_int = ("num_steps", "num_epochs", "num_minibatches")
        for name in positive_int:
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise ValueError(f"ppo.{name} must be a positive integer, got {value!r}")
        for name in ("gamma", "gae_lambda"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"ppo.{name} must be in [0, 1], got {getattr(self, name)!r}")
        for name in ("clip_ratio", "learning_rate", "max_grad_norm", "desired_kl", "adam_eps"):
            if not getattr(self, name) > 0:
                raise ValueError(f"ppo.{name} must be > 0, got {getattr(self, name)!r}")
        for name in ("value_loss_coef", "entropy_coef"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"ppo.{name} must be >= 0, got {getattr(self, name)!r}")
        if self.lr_schedule not in SCHEDULES:
            raise ValueError(
                f"ppo.lr_schedule must be one of {SCHEDULES}, got {self.lr_schedule!r}"
            )
        if self.target_kl is not None and not self.target_kl > 0:
            raise ValueError(f"ppo.target_kl must be > 0 or null, got {self.target_kl!r}")
        if not 0 < self.min_learning_rate <= self.max_learning_rate:
            raise ValueError("ppo.min_learning_rate must be > 0 and <= ppo.max_learning_rate")
