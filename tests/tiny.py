"""The smallest real training config (2 MuJoCo envs x 8 steps, one epoch of 2 minibatches),
shared by the tests that need a trained run but not a trained policy."""

from cpg_actor.config import TrainConfig
from cpg_actor.ppo import PPOConfig


def tiny_config(agent: str, iterations: int = 2, **fields) -> TrainConfig:
    return TrainConfig(
        agent=agent,
        num_envs=2,
        total_steps=iterations * 2 * 8,
        ppo=PPOConfig(num_steps=8, num_epochs=1, num_minibatches=2),
        eval_interval=0,
        **fields,
    )
