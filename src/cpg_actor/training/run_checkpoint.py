"""Checkpoints of a run: where they are written, what a PPO run's holds, and resuming from one
(the loop writes them through :class:`cpg_actor.training.hooks.Checkpoints`).

A checkpoint holds, besides the networks, the optimiser, the normalisers and the RNG streams,
the episodes in progress (:meth:`cpg_actor.training.rollout.Rollout.state`: MuJoCo's full
physics state of every robot, the episode clocks, each env's random generator, the last
observation, every env's CPG state and the episode statistics). A resumed run therefore
continues exactly where the checkpoint was taken: it equals the uninterrupted run bit for bit
(MuJoCo; PyBullet restores joint states but not its contact caches). A seed of a group
(:mod:`cpg_actor.training.many_seeds`) names its group; the first seed's holds the whole env.
One seed's checkpoint resumed as a run of its own continues from new episodes (a group of
one: from its episodes), and says so (:attr:`Runner.resumed_out_of_group`). Files are written
atomically (:func:`cpg_actor.training.checkpoint.atomic_save`): ``iter_<N>.pt``, then
``last.pt``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from cpg_actor.training import checkpoint

if TYPE_CHECKING:
    from cpg_actor.training.runner import Runner


def last_path(run_dir: Path | None) -> Path | None:
    """``RUN_DIR/checkpoints/last.pt`` once written; None before or without a run dir."""
    if run_dir is None:
        return None
    path = run_dir / "checkpoints" / "last.pt"
    return path if path.exists() else None


def save(data: dict[str, Any], run_dir: Path, iteration: int) -> Path:
    """``checkpoints/iter_<iteration>.pt``, then ``last.pt``, each written atomically."""
    folder = run_dir / "checkpoints"
    path = folder / f"iter_{iteration:06d}.pt"
    checkpoint.atomic_save(data, path)
    checkpoint.atomic_save(data, folder / "last.pt")
    return path


def run_state(runner: Any) -> dict[str, Any]:
    """What every run's checkpoint holds (PPO's and the open-loop search's): the format, the
    run's agent and config, the counters, the agent, the observation normaliser, the time
    trained and the RNG streams."""
    return {
        "format": checkpoint.CHECKPOINT_FORMAT,
        "version": checkpoint.CHECKPOINT_VERSION,
        "agent": runner.config.agent,
        "config": runner.config.to_dict(),
        "iteration": runner.iteration,
        "global_step": runner.global_step,
        "agent_state": runner.agent.state_dict(),
        "normalizer": runner.normalizer.state_dict(),
        "train_wall": runner.train_wall,
        "rng": checkpoint.rng_state(),
    }


def read(path: Path, agent: str) -> dict[str, Any]:
    """The checkpoint at ``path``, checked to be one of a run of ``agent``."""
    data = checkpoint.load_checkpoint(path)
    checkpoint.check_checkpoint_run(path, data, agent)
    return data


def restore_run_state(runner: Any, path: Path, data: dict[str, Any]) -> None:
    """Put :func:`run_state`'s part of checkpoint ``data`` (:func:`read` from ``path``) back
    into ``runner``; a ValueError if its networks are not the agent's."""
    try:
        runner.agent.load_state_dict(data["agent_state"])
        runner.normalizer.load_state_dict(data["normalizer"])
    except RuntimeError as error:
        raise ValueError(
            f"checkpoint {path} does not match this agent's networks: {error}"
        ) from None
    runner.train_wall = float(data.get("train_wall", 0.0))
    runner.iteration = int(data["iteration"])
    runner.global_step = int(data["global_step"])
    runner.run_log.purge_step = runner.global_step + 1  # TensorBoard drops what came after
    checkpoint.set_rng_state(data["rng"])


def ppo_state(runner: Runner) -> dict[str, Any]:
    """What a PPO run's checkpoint holds (the module docstring)."""
    group = {} if runner.seed_group is None else {"seed_group": runner.seed_group}
    return {
        **run_state(runner),
        **group,
        "reward_normalizer": runner.reward_normalizer.state_dict(),
        "optimizer": runner.ppo.optimizer.state_dict(),
        "learning_rate": runner.ppo.learning_rate,
        "env_seed": runner.env_seed,
        "recent": runner.rollout.episodes.recent_state(),
        "episodes": runner.rollout.state(),
    }


def load_ppo_state(runner: Runner, path: Path) -> None:
    """Continue ``runner``'s training from ``path``: networks, optimiser, normalisers, RNG
    streams, counters and the episodes in progress."""
    data = read(path, runner.config.agent)
    restore_run_state(runner, path, data)
    runner.ppo.optimizer.load_state_dict(data["optimizer"])
    runner.ppo.set_learning_rate(data["learning_rate"])
    if "reward_normalizer" in data:  # absent from checkpoints of earlier versions
        runner.reward_normalizer.load_state_dict(data["reward_normalizer"])
    runner.rollout.episodes.load_recent(data["recent"])
    runner.env_seed = data.get("env_seed")
    episodes = data.get("episodes")
    group = data.get("seed_group")
    if group is not None and runner.seed_group is None:  # one seed of a group, alone
        runner.resumed_out_of_group = group
        whole = ((episodes or {}).get("env") or {}).get("group_env")
        # the group's env is this seed's own only in a group of one seed
        episodes = {**episodes, "env": whole} if len(group["seeds"]) == 1 and whole else None
    if episodes is not None and runner.env.saves_state:
        runner.rollout.restore(episodes)
    else:  # a checkpoint without episodes (an env that cannot save them): new ones
        runner.start_episodes()
