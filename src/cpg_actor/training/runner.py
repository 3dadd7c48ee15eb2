"""PPO's training loop: collect a rollout, update, call the hooks; repeat to the budget.

The run is built from its config apart from the loop (:mod:`cpg_actor.training.build`); the
rollout carries the CPG state per env (:mod:`cpg_actor.training.rollout`); PPO updates
(:class:`cpg_actor.ppo.PPO`); evaluation, logging, the progress display and checkpoints are
hooks (:mod:`cpg_actor.training.hooks`; the checkpoints' content in
:mod:`cpg_actor.training.run_checkpoint`).

Evaluation during training. Every ``eval_interval`` iterations (and before the first and
after the last) the policy's mean action runs one episode on each of ``eval_episodes``
environments of its own, always reset with the same seed; the mean return and the env's
episode metrics are logged as ``eval/return`` and ``eval/<metric>``. It draws no random
numbers and touches neither the training envs nor the normaliser, so a run trains the same
with or without it. ``time/train_wall`` is the run's wall time without evaluation and
checkpoints (what ``benchmarks/time_to_hop.py`` reports).

Reproducibility. Everything random is seeded from ``TrainConfig.seed``
(:mod:`cpg_actor.training.seeding`): torch (action noise, minibatch order, initialisation),
numpy and python RNGs, and the environments' ``reset(seed=...)`` at the start of the run. A
resumed run equals the uninterrupted one bit for bit (:mod:`cpg_actor.training.run_checkpoint`).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import torch

from cpg_actor.config import TrainConfig
from cpg_actor.files import atomic_write_text
from cpg_actor.ppo import NonFiniteLossError
from cpg_actor.training import run_checkpoint
from cpg_actor.training.build import build_ppo_run
from cpg_actor.training.compile_stance import CompileStance
from cpg_actor.training.evaluation import TrainingEvaluation
from cpg_actor.training.hooks import (
    Checkpoints,
    Hook,
    Iteration,
    StopWhen,
    loop_hooks,
    ppo_progress,
    ppo_row,
    run_loop,
)
from cpg_actor.training.rollout import NonFiniteActionsError, Rollout
from cpg_actor.training.run_log import RunLog
from cpg_actor.training.seeding import WARM_START_SEED_KEY, derived_seed
from cpg_actor.training.threads import update_threads


class TrainingDiverged(RuntimeError):
    """A loss became NaN/inf; the run stopped and the last good checkpoint was kept."""


class Runner:
    """Builds env, agent, normaliser and PPO from a :class:`TrainConfig` and trains.

    ``run_dir`` (optional) receives checkpoints, ``metrics.jsonl`` and TensorBoard events;
    ``env`` and ``eval_env`` replace the robot's envs (tests; the agent is still built for the
    config's robot, ``TrainConfig.robot``: its CPG layouts and start gait); ``hooks``
    are called after evaluation, logging and progress, before checkpoints (a hook that sets
    ``Iteration.stop`` ends the run with a checkpoint).
    """

    def __init__(
        self,
        config: TrainConfig,
        run_dir: Path | None = None,
        env: Any = None,
        progress: bool = False,
        tensorboard: bool = True,
        eval_env: Any = None,
        progress_interval: float = 30.0,
        hooks: Sequence[Hook] = (),
    ) -> None:
        config.validate()
        if env is not None and eval_env is None and config.eval_interval > 0:
            raise ValueError(
                "a Runner given its own env needs an eval_env too (the evaluation envs), "
                "or a config with eval_interval=0"
            )
        self.config = config
        self.run_dir = Path(run_dir) if run_dir is not None else None
        self.show_progress = progress
        self.run_log = RunLog(self.run_dir, tensorboard)
        run = build_ppo_run(config, env)
        self.device, self.robot, self.spec, self.env = run.device, run.robot, run.spec, run.env
        self.agent, self.normalizer, self.policy = run.agent, run.normalizer, run.policy
        self.reward_normalizer, self.ppo, self.storage = run.reward_normalizer, run.ppo, run.storage
        self.rollout = Rollout(config, run)
        self.compile_stance = CompileStance(config.ppo, self.device)
        low, high = self.policy.action_low, self.policy.action_high
        self.evaluation = TrainingEvaluation(
            config, self.robot, self.agent, self.normalizer, low, high, eval_env
        )
        self.hooks: list[Hook] = [
            *loop_hooks(self.evaluation, ppo_row, ppo_progress, progress, progress_interval),
            *hooks,
        ]
        self.iteration = 0
        # env steps so far; a run that counts its start gait's search begins at its steps
        self.global_step = config.search_steps
        self.train_wall = 0.0  # seconds of collection + update, over the whole run
        self.env_seed: int | None = None  # the training envs' last reset seed
        self.last_evaluation: dict[str, float] | None = None  # as the hooks recorded them
        self.last_row: dict[str, float] = {}
        self._resumed = False  # loaded from a checkpoint: no warm start, no "before" again
        # the run's seed group, named in its checkpoints (cpg_actor.training.many_seeds)
        self.seed_group: dict[str, Any] | None = None
        # the group this run was a seed of, resumed alone from its checkpoint: not as exact
        self.resumed_out_of_group: dict[str, Any] | None = None

    # -- the loop ----------------------------------------------------------------------------
    def learn(self, stop_when: Callable[[dict[str, float]], bool] | None = None) -> None:
        """Train to ``config.total_steps``, calling the hooks (module docstring).

        ``stop_when(evaluation)``, if given, is called with each evaluation's scalars
        (``eval/return``, ``eval/hop_height``, ...); training stops after the first one for
        which it returns True (with a checkpoint, if the run has a directory)."""
        if self.run_dir is not None:
            self.run_dir.mkdir(parents=True, exist_ok=True)
        fresh = self.iteration == 0 and not self._resumed  # a new run, not one resumed at 0
        if fresh and self.spec.warm_start is not None:
            self.run_warm_start()
        if not self.rollout.started:
            self.start_episodes()
        stop = [StopWhen(stop_when)] if stop_when is not None else []
        hooks = [*self.hooks, *stop, Checkpoints()]  # checkpoints save what the rest decided
        run_loop(self, hooks, fresh, lambda: self.iteration < self.config.num_iterations)

    @property
    def planned_steps(self) -> int:
        """The run's env steps at its end (its start gait's search counted)."""
        cfg = self.config
        return cfg.search_steps + cfg.num_iterations * cfg.steps_per_iteration

    def train_iteration(self) -> Iteration:
        """One rollout and one PPO update; the counters advance."""
        start = time.perf_counter()
        self.ppo.schedule(self.iteration, self.config.num_iterations)
        collected = self.collect()
        return self.learn_from(collected, time.perf_counter() - start)

    def learn_from(self, collected: dict[str, float], collect_time: float) -> Iteration:
        """The PPO update of the rollout just collected (in ``collect_time`` seconds, its
        ``simulation_time`` in env steps); the counters advance."""
        cfg = self.config
        start_learn = time.perf_counter()
        try:
            stats = self.update()
        except NonFiniteLossError as error:
            raise self._diverged(error) from None
        learn_time = time.perf_counter() - start_learn
        self.iteration += 1
        self.global_step += cfg.steps_per_iteration
        self.train_wall += collect_time + learn_time
        timing = {
            "SPS": cfg.steps_per_iteration / (collect_time + learn_time),
            "collection": collect_time,
            "simulation": collected["simulation_time"],
            "inference": collect_time - collected["simulation_time"],
            "learning": learn_time,
        }
        return Iteration(self.iteration, self.iteration == cfg.num_iterations, stats, timing)

    def start_episodes(self) -> None:
        """Reset every environment and every agent state (at the start of a run)."""
        self.env_seed = derived_seed(self.config.seed, self.iteration)
        self.rollout.start(self.env_seed)

    def collect(self) -> dict[str, float]:
        """One rollout of ``ppo.num_steps`` control steps in every environment."""
        with self.compile_stance.calls():
            try:
                return self.rollout.collect()
            except NonFiniteActionsError as error:
                raise self._diverged(error) from None

    def update(self) -> dict[str, float]:
        """The PPO update of the collected rollout, on :func:`update_threads` torch threads
        (the simulator's threads are idle meanwhile); the rollout runs on ``torch_threads``."""
        torch.set_num_threads(update_threads(self.config))
        try:
            with self.compile_stance.calls():
                stats = self.ppo.update(self.storage)
        finally:
            torch.set_num_threads(self.config.torch_threads)
        self.compile_stance.mark_warm()  # a whole iteration has run
        return stats

    def _diverged(self, error: Exception) -> TrainingDiverged:
        return TrainingDiverged(
            f"iteration {self.iteration + 1}: {error}. "
            f"Last good checkpoint: {self.last_checkpoint_path()}"
        )

    def run_warm_start(self) -> list[float]:
        """The agent's supervised warm start (e.g. cho2019-warm), before any PPO iteration.

        Its environment seed is derived from ``(seed, WARM_START_SEED_KEY)``; the episodes it
        ran are discarded (:meth:`start_episodes` resets every env afterwards). The loss of
        each epoch goes to TensorBoard (``warm_start/loss``) and ``RUN_DIR/warm_start.json``.
        """
        cfg = self.config
        seed = derived_seed(cfg.seed, WARM_START_SEED_KEY)
        normalizer = self.normalizer if cfg.ppo.normalize_observations else None
        losses = self.spec.warm_start(
            self.agent, normalizer, self.env.unwrapped, cfg, seed, self.robot
        )
        self.rollout.started = False
        if self.show_progress:
            print(
                f"warm start: {len(losses)} epochs, loss {losses[0]:.4g} -> {losses[-1]:.4g}",
                flush=True,
            )
        if self.run_dir is not None:
            self.run_dir.mkdir(parents=True, exist_ok=True)
            atomic_write_text(json.dumps({"loss": losses}) + "\n", self.run_dir / "warm_start.json")
            for epoch, loss in enumerate(losses):
                self.run_log.scalar("warm_start/loss", loss, epoch)
        return losses

    def run_evaluation(self) -> dict[str, float]:
        """Deterministic episodes on the evaluation envs, now (see the module docstring)."""
        return self.evaluation()

    # -- checkpoints (cpg_actor.training.run_checkpoint) -----------------------------------
    def last_checkpoint_path(self) -> Path | None:
        return run_checkpoint.last_path(self.run_dir)

    def state_dict(self) -> dict[str, Any]:
        return run_checkpoint.ppo_state(self)

    def save_checkpoint(self) -> Path:
        assert self.run_dir is not None
        return run_checkpoint.save(self.state_dict(), self.run_dir, self.iteration)

    def load_checkpoint(self, path: Path) -> None:
        """Continue training from ``path``. To act with a trained agent, see
        :func:`cpg_actor.deploy.load_policy`."""
        run_checkpoint.load_ppo_state(self, path)
        self._resumed = True

    def close(self) -> None:
        self.run_log.close()
        self.env.close()
        for hook in self.hooks:
            hook.close()
