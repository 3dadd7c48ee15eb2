"""Named starting points for a training run: ``cpg-actor train --preset NAME``.

A preset is a set of config values applied over :class:`cpg_actor.config.TrainConfig`'s
defaults, before ``--config``, the flags and ``--set`` (which all win over it); its name is
saved in the run's ``config.yaml`` (``preset``).

* ``paper``: OpenAI Baselines' ppo2 settings for MuJoCo tasks, the framework the paper used
  (every number and its source: :class:`cpg_actor.ppo.PPOConfig`). These are the dataclass
  defaults; the preset only adds ``ppo.compile`` (the same algorithm, its minibatch loss
  compiled by ``torch.compile``: 2 to 2.8x faster updates, ``benchmarks/train_throughput.py``).
* ``throughput``: fewer, larger gradient steps per sample and more envs per Python step,
  chosen to reach the same evaluation thresholds in less wall time on a CPU
  (``benchmarks/time_to_hop.py``; the numbers in ``docs/training.md``, "Presets").
"""

from __future__ import annotations

from typing import Any

PRESETS: dict[str, dict[str, Any]] = {
    "paper": {"ppo": {"compile": True}},
    # 32 envs x 64 steps, minibatches of 128: 160 gradient steps per 2,048 samples (paper: 320)
    "throughput": {
        "num_envs": 32,
        "eval_interval": 10,
        "ppo": {"num_steps": 64, "num_epochs": 10, "num_minibatches": 16, "compile": True},
    },
}


def preset_values(name: str) -> dict[str, Any]:
    """The config values of preset ``name`` (a nested mapping); ValueError if unknown."""
    if name not in PRESETS:
        raise ValueError(f"unknown preset {name!r}; available: {', '.join(sorted(PRESETS))}")
    return {"preset": name, **PRESETS[name]}
