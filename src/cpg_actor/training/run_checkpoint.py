"""Checkpoints of a PPO run: what one holds, when the loop writes one, and resuming from one.

A checkpoint holds, besides the networks, the optimiser, the normalisers and the RNG streams,
the episodes in progress (:meth:`cpg_actor.training.rollout.Rollout.state`: MuJoCo's full
physics state of every robot, the episode clocks, each env's random generator, the last
observation, every env's CPG state and the episode statistics). A resumed run therefore
continues exactly where the checkpoint was taken: it equals the uninterrupted run bit for bit
(MuJoCo; PyBullet restores joint states but not its contact caches). Files are written
atomically (:func:`cpg_actor.training.checkpoint.atomic_save`): ``iter_<N>.pt``, then
``last.pt``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from cpg_actor.training import checkpoint
from cpg_actor.training.hooks import Hook, Iteration

if TYPE_CHECKING:
    from cpg_actor.training.runner import Runner


class Checkpoints(Hook):
    """Writes ``RUN_DIR/checkpoints/`` every ``checkpoint_interval`` iterations, after the last,
    when a hook stops the run, and before the first iteration of a new run (the untrained or
    warm-started agent: a "before"); nothing without a run directory. The loop calls it after
    every other hook, so that it saves what they decided."""

    def start(self, runner: Runner, fresh: bool) -> None:
        if fresh and runner.run_dir is not None:
            self.save(runner)

    def iteration(self, runner: Runner, it: Iteration) -> None:
        at_interval = it.number % runner.config.checkpoint_interval == 0
        if runner.run_dir is not None and (at_interval or it.last or it.stop):
            self.save(runner)

    @staticmethod
    def last_path(runner: Runner) -> Path | None:
        """``RUN_DIR/checkpoints/last.pt`` once written; None before or without a run dir."""
        if runner.run_dir is None:
            return None
        path = runner.run_dir / "checkpoints" / "last.pt"
        return path if path.exists() else None

    @staticmethod
    def state(runner: Runner) -> dict[str, Any]:
        return {
            "format": checkpoint.CHECKPOINT_FORMAT,
            "version": checkpoint.CHECKPOINT_VERSION,
            "agent": runner.config.agent,
            "config": runner.config.to_dict(),
            "iteration": runner.iteration,
            "global_step": runner.global_step,
            "agent_state": runner.agent.state_dict(),
            "normalizer": runner.normalizer.state_dict(),
            "reward_normalizer": runner.reward_normalizer.state_dict(),
            "train_wall": runner.train_wall,
            "optimizer": runner.ppo.optimizer.state_dict(),
            "learning_rate": runner.ppo.learning_rate,
            "rng": checkpoint.rng_state(),
            "env_seed": runner.env_seed,
            "recent": runner.rollout.episodes.recent_state(),
            "episodes": runner.rollout.state(),
        }

    def save(self, runner: Runner) -> Path:
        assert runner.run_dir is not None
        data = self.state(runner)
        folder = runner.run_dir / "checkpoints"
        path = folder / f"iter_{runner.iteration:06d}.pt"
        checkpoint.atomic_save(data, path)
        checkpoint.atomic_save(data, folder / "last.pt")
        return path

    @staticmethod
    def load(runner: Runner, path: Path) -> None:
        """Continue ``runner``'s training from ``path``: networks, optimiser, normalisers, RNG
        streams, counters and the episodes in progress."""
        data = checkpoint.load_checkpoint(path)
        checkpoint.check_checkpoint_run(path, data, runner.config.agent)
        try:
            runner.agent.load_state_dict(data["agent_state"])
            runner.normalizer.load_state_dict(data["normalizer"])
        except RuntimeError as error:
            raise ValueError(
                f"checkpoint {path} does not match this agent's networks: {error}"
            ) from None
        runner.ppo.optimizer.load_state_dict(data["optimizer"])
        runner.ppo.set_learning_rate(data["learning_rate"])
        if "reward_normalizer" in data:  # absent from checkpoints of earlier versions
            runner.reward_normalizer.load_state_dict(data["reward_normalizer"])
        runner.train_wall = float(data.get("train_wall", 0.0))
        runner.iteration = data["iteration"]
        runner.global_step = data["global_step"]
        runner.run_log.purge_step = runner.global_step + 1  # TensorBoard drops what came after
        runner.rollout.episodes.load_recent(data["recent"])
        checkpoint.set_rng_state(data["rng"])
        runner.env_seed = data.get("env_seed")
        episodes = data.get("episodes")
        if episodes is not None and runner.env.saves_state:
            runner.rollout.restore(episodes)
        else:  # a checkpoint without episodes (an env that cannot save them): new ones
            runner.start_episodes()
