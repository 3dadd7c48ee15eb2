"""Every number of the PPO algorithm, in one dataclass."""

from __future__ import annotations

import math
from dataclasses import dataclass

from cpg_actor.limits import (
    MAX_EPOCHS,
    MAX_ROLLOUT_SAMPLES,
    MAX_ROLLOUT_STEPS,
    brief,
    check_int,
)

SCHEDULES = ("fixed", "linear", "adaptive")
CPG_SCHEDULES = ("fixed", "follow")


@dataclass
class PPOConfig:
    """PPO hyper-parameters. The defaults are the ``paper`` preset: OpenAI Baselines' ppo2
    settings for MuJoCo tasks (the paper's CPG-Actor was trained in a Baselines-based
    framework), which are also Stable-Baselines3's PPO defaults. Sources, per number:
    ``baselines/ppo2/defaults.py`` (``mujoco()``: nsteps 2048, nminibatches 32, lam 0.95,
    gamma 0.99, noptepochs 10, log_interval 1, ent_coef 0.0, lr 3e-4 linearly decayed to 0,
    cliprange 0.2), ``baselines/ppo2/ppo2.py`` (vf_coef 0.5, max_grad_norm 0.5),
    ``baselines/ppo2/model.py`` (Adam eps 1e-5, value loss clipped with the same cliprange,
    advantages normalised per minibatch) and ``baselines/common/vec_env/vec_normalize.py``
    (observations and rewards normalised, both clipped to +-10, discount 0.99, eps 1e-8), which
    ``baselines/run.py`` wraps around every MuJoCo env. See ``docs/training.md``, "Presets".

    One iteration collects ``num_steps`` control steps in each of the runner's environments,
    then runs ``num_epochs`` passes over that batch in ``num_minibatches`` minibatches.
    Baselines steps 1 env for 2048 steps; the preset steps 16 envs for 128 steps: the same
    2,048 samples per update, the same 64-sample minibatches and 320 gradient steps per update.
    """

    num_steps: int = 128  # control steps per environment per iteration (rollout length)
    num_epochs: int = 10
    num_minibatches: int = 32
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_ratio: float = 0.2  # epsilon of the clipped surrogate (and of the value clip)
    clip_value_loss: bool = True  # Baselines ppo2 clips; SB3 does not (clip_range_vf=None)
    value_loss_coef: float = 0.5
    entropy_coef: float = 0.0
    normalize_advantages: bool = True  # per minibatch
    max_grad_norm: float = 0.5
    learning_rate: float = 3e-4
    lr_schedule: str = "linear"  # fixed | linear (to 0 at the last iteration) | adaptive (KL)
    desired_kl: float = 0.01  # adaptive schedule: lr /1.5 above 2x, *1.5 below 0.5x
    min_learning_rate: float = 1e-5
    max_learning_rate: float = 1e-2
    target_kl: float | None = None  # stop the epochs of an iteration once approx_kl exceeds it
    # the learning rate of what acts through the CPG (the CPG-Actor's vector V and feedback
    # MLP), fixed, outside the schedule. None (the paper): the schedule's, as every other
    # parameter. The adaptive schedule needs it: V and the feedback change the action only by
    # their one-step effect, so the KL hardly sees them, the rate climbs to its cap and they
    # drift (on the quadruped the hip and knee frequencies split within 10 iterations and the
    # robots fall; docs/quadruped.md, "Training"). Agents without a CPG ignore it.
    cpg_learning_rate: float | None = None
    # how that rate moves: "fixed" (as above), or "follow": cpg_learning_rate times
    # min(1, lr / learning_rate), lr the schedule's rate for the others. With a k-step
    # gradient (bptt_steps > 1) the KL sees the CPG, and a fixed rate keeps moving V and the
    # feedback after the KL has pushed the others' rate to its floor; "follow" slows them
    # with it, never above their own rate
    cpg_lr_schedule: str = "fixed"
    adam_eps: float = 1e-5
    normalize_observations: bool = True
    # VecNormalize's reward scaling: rewards divided by the running std of each env's
    # discounted return (discount ``gamma``), clipped to +-10; training only, logs stay raw
    normalize_rewards: bool = True
    # torch.compile the minibatch loss (forward and backward) and the rollout's policy step
    # (Policy.compile: normaliser, agent, sampling): the same algorithm in fewer, fused
    # kernels, after compiles of a few seconds per run; needs a C++ compiler (inductor). On
    # the CPU the whole gradient step (loss, gradient, clip, the adaptive rate, Adam) is one
    # compiled function (ppo/train_step.py). Results differ from eager in the last bits, not
    # run to run.
    compile: bool = False
    # with ``compile`` on the CPU: the whole gradient step as one compiled function (above).
    # False: the separate calls (compiled loss, autograd, clip, fused Adam), the path a CUDA
    # run always takes, to compare the two (docs/gpu.md, "Learning on MJX")
    fused_step: bool = True
    # with ``compile`` on the CPU: once a runner has made one iteration (every compiled
    # function built for the shapes and settings its loop uses), dynamo stops checking their
    # guards before each compiled call of the rollout and the update
    # (``torch.compiler.set_stance(skip_guard_eval_unsafe=True)``; training/compile_stance.py),
    # which saves their per-call cost. The same compiled code runs, so the same numbers;
    # false: checked at every call, as torch.compile does
    skip_guard_checks: bool = True
    # the gradient through the CPG (beyond the paper): the PPO loss replays each step's CPG
    # state from the state stored k - 1 steps earlier, so the gradient reaches the CPG and
    # feedback parameters through k steps (truncated BPTT). 1 is the paper's one-step
    # gradient; agents without a recurrent state accept only 1. Cost: k actor passes.
    bptt_steps: int = 1

    def validate(self) -> None:
        # every count bounded (cpg_actor.limits); the rollout's samples, num_envs x num_steps,
        # are bounded by TrainConfig.validate
        for name, high in (
            ("num_steps", MAX_ROLLOUT_STEPS),
            ("num_epochs", MAX_EPOCHS),
            ("num_minibatches", MAX_ROLLOUT_SAMPLES),
            ("bptt_steps", MAX_ROLLOUT_STEPS),
        ):
            check_int(getattr(self, name), f"ppo.{name}", 1, high)
        numbers = (
            "gamma", "gae_lambda", "clip_ratio", "value_loss_coef", "entropy_coef",
            "max_grad_norm", "learning_rate", "desired_kl", "min_learning_rate",
            "max_learning_rate", "adam_eps",
        )  # fmt: skip
        for name in numbers:
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"ppo.{name} must be a number, got {brief(value)}")
            if not math.isfinite(value):
                raise ValueError(f"ppo.{name} must be finite, got {brief(value)}")
        for name in ("gamma", "gae_lambda"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"ppo.{name} must be in [0, 1], got {brief(getattr(self, name))}")
        for name in ("clip_ratio", "learning_rate", "max_grad_norm", "desired_kl", "adam_eps"):
            if not getattr(self, name) > 0:
                raise ValueError(f"ppo.{name} must be > 0, got {brief(getattr(self, name))}")
        for name in ("value_loss_coef", "entropy_coef"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"ppo.{name} must be >= 0, got {brief(getattr(self, name))}")
        if self.lr_schedule not in SCHEDULES:
            raise ValueError(
                f"ppo.lr_schedule must be one of {SCHEDULES}, got {brief(self.lr_schedule)}"
            )
        if self.target_kl is not None and not self.target_kl > 0:
            raise ValueError(f"ppo.target_kl must be > 0 or null, got {brief(self.target_kl)}")
        rate = self.cpg_learning_rate
        if rate is not None and (
            isinstance(rate, bool) or not isinstance(rate, (int, float)) or not 0 < rate < 1
        ):
            raise ValueError(
                f"ppo.cpg_learning_rate must be a number in (0, 1) or null, got {brief(rate)}"
            )
        if self.cpg_lr_schedule not in CPG_SCHEDULES:
            raise ValueError(
                f"ppo.cpg_lr_schedule must be one of {CPG_SCHEDULES}, "
                f"got {brief(self.cpg_lr_schedule)}"
            )
        if self.cpg_lr_schedule == "follow" and self.cpg_learning_rate is None:
            raise ValueError(
                "ppo.cpg_lr_schedule=follow needs ppo.cpg_learning_rate (the rate it scales)"
            )
        if self.bptt_steps > self.num_steps:
            raise ValueError(
                f"ppo.bptt_steps ({self.bptt_steps}) must be <= ppo.num_steps "
                f"({self.num_steps}): the window lies inside one rollout"
            )
        if not 0 < self.min_learning_rate <= self.max_learning_rate:
            raise ValueError("ppo.min_learning_rate must be > 0 and <= ppo.max_learning_rate")
