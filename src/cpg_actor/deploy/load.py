"""A trained run's :class:`~cpg_actor.training.policy.Policy`, rebuilt from its checkpoint with
no trainer, env or optimiser::

    policy = load_policy("runs/cpg-actor")      # checkpoints/last.pt (its saved config)
    policy.reset(num_envs=1)
    action = policy.act(obs).action             # obs (1, obs_dim) float32, numpy or torch
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch

from cpg_actor.agents import get_agent_spec
from cpg_actor.config import TrainConfig
from cpg_actor.ppo.normalizer import RunningNormalizer
from cpg_actor.robots.registry import get_robot
from cpg_actor.training.build import make_env
from cpg_actor.training.checkpoint import check_checkpoint_run, load_checkpoint
from cpg_actor.training.policy import Policy


def load_policy(
    path: str | Path,
    env_config: Any = None,
    device: torch.device | str = "cpu",
    run_config: Any = None,
) -> Policy:
    """The policy of a run directory (``checkpoints/last.pt``) or of a checkpoint file.

    The agent is rebuilt from the config saved in the checkpoint; the action bounds and
    observation size come from that agent's environment (built once, then closed).
    ``env_config`` replaces the run's env config (e.g. another simulator); ``device`` is where
    the agent runs (default the CPU, wherever it was trained). ``run_config``: the
    ``TrainConfig`` of the run the checkpoint belongs to (``cpg-actor eval`` and ``export``):
    a ValueError when the checkpoint was trained with another agent or on another robot
    (:func:`cpg_actor.training.checkpoint.check_checkpoint_run`), and its env config is used unless
    ``env_config`` is given. Call :meth:`Policy.reset` with the number of envs before acting.
    """
    path = Path(path)
    checkpoint = path / "checkpoints" / "last.pt" if path.is_dir() else path
    data = load_checkpoint(checkpoint)
    if run_config is not None:
        check_checkpoint_run(checkpoint, data, run_config.agent, run_config.robot)
        env_config = run_config.env if env_config is None else env_config
    config = TrainConfig.from_dict(data["config"])
    if env_config is not None:
        config.env = env_config
    spec, plugin = get_agent_spec(config.agent), get_robot(config.robot)
    env = make_env(config, plugin, 1, 1)
    try:
        low = np.asarray(env.single_action_space.low, dtype=np.float32)
        high = np.asarray(env.single_action_space.high, dtype=np.float32)
        obs_dim = int(env.single_observation_space.shape[0])
        agent = spec.build(config.agent_config, env, plugin)
        robot = getattr(env, "robot", None)
    finally:
        env.close()
    normalizer = RunningNormalizer(obs_dim)
    try:
        agent.load_state_dict(data["agent_state"])
        normalizer.load_state_dict(data["normalizer"])
    except RuntimeError as error:
        raise ValueError(
            f"checkpoint {checkpoint} does not match its agent's networks: {error}"
        ) from None
    agent.eval()
    agent.to(device)
    normalizer.to(device)
    policy = Policy(agent, normalizer, low, high, config.ppo.normalize_observations)
    policy.config = config  # the run's resolved config, as saved in the checkpoint
    policy.robot = robot
    return policy
