"""The smallest real training config (2 MuJoCo envs x 8 steps, one epoch of 2 minibatches)
and a run trained with it, shared by the tests that need a trained run but not a trained
policy."""

from pathlib import Path

from cpg_actor.config import TrainConfig, apply_dict
from cpg_actor.ppo import PPOConfig
from cpg_actor.training.runner import Runner


def tiny_config(agent: str, iterations: int = 2, **fields) -> TrainConfig:
    return TrainConfig(
        agent=agent,
        num_envs=2,
        total_steps=iterations * 2 * 8,
        ppo=PPOConfig(num_steps=8, num_epochs=1, num_minibatches=2),
        eval_interval=0,
        **fields,
    )


def trained_run(path: Path, agent: str, robot: str = "hopper", **changes) -> Path:
    """A tiny training run in ``path``, with its config.yaml as `cpg-actor train` writes it;
    ``changes``: config values (``seed=1``, ``env={...}``)."""
    config = tiny_config(agent)
    apply_dict(config, {"robot": robot, **changes}, "")
    runner = Runner(config, run_dir=path, tensorboard=False)
    runner.learn()
    runner.close()
    config.save(path / "config.yaml")
    return path
