"""What the training loop calls around its iterations: evaluation, logging, the progress
display (here), checkpoints (:mod:`cpg_actor.training.run_checkpoint`) and any hook of the
caller's own (``Runner(hooks=...)``).

The loop calls every hook in order: ``start`` before the first iteration of
:meth:`~cpg_actor.training.runner.Runner.learn`, ``iteration`` after each PPO update with the
:class:`Iteration` the earlier hooks filled in (the evaluation, a request to stop), and
``end`` when ``learn`` returns or raises; ``close`` with the runner. Hooks see the runner and
change nothing it trains: evaluation runs on envs of its own and draws no random numbers, so
a run trains the same with or without it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from cpg_actor.training.evaluation import TrainingEvaluation
from cpg_actor.training.progress import evaluation_text, make_progress, metrics_text, return_text

if TYPE_CHECKING:
    from cpg_actor.training.runner import Runner


@dataclass
class Iteration:
    """One iteration as the hooks see it, filled in as they run."""

    number: int  # iterations done, this one included
    last: bool  # the run's last iteration
    stats: dict[str, float]  # the PPO update's statistics (losses, learning rates, ...)
    timing: dict[str, float]  # SPS and seconds of collection, simulation, inference, learning
    evaluation: dict[str, float] | None = None  # the evaluation's row, if it ran
    stop: bool = False  # stop after this iteration (checkpoints save it first)


class Hook:
    """A hook of the training loop; every method does nothing unless overridden."""

    def start(self, runner: Runner, fresh: bool) -> None:
        """Before the first iteration; ``fresh``: a new run, not one resumed."""

    def iteration(self, runner: Runner, it: Iteration) -> None:
        """After each iteration's update."""

    def end(self, runner: Runner) -> None:
        """When ``learn`` returns or raises."""

    def close(self) -> None:
        """Release what the hook holds (the runner closes)."""


class Evaluation(Hook):
    """Deterministic episodes every ``eval_interval`` iterations, after the last and before
    the first of a new run (the untrained or warm-started agent, logged alone); none with
    ``eval_interval`` 0. See :class:`cpg_actor.training.evaluation.TrainingEvaluation`."""

    def __init__(self, runs: TrainingEvaluation) -> None:
        self.runs = runs

    def evaluate(self, runner: Runner) -> dict[str, float]:
        low, high = runner.policy.action_low, runner.policy.action_high
        return self.runs(runner.agent, runner.normalizer, low, high)

    def start(self, runner: Runner, fresh: bool) -> None:
        if fresh and runner.config.eval_interval > 0:
            runner.last_evaluation = evaluation = self.evaluate(runner)
            row = {**evaluation, "time/train_wall": runner.train_wall}
            runner.run_log.write(runner.iteration, runner.global_step, row)

    def iteration(self, runner: Runner, it: Iteration) -> None:
        interval = runner.config.eval_interval
        if interval > 0 and (it.number % interval == 0 or it.last):
            it.evaluation = runner.last_evaluation = self.evaluate(runner)

    def close(self) -> None:
        self.runs.close()


class StopWhen(Hook):
    """Stop after the first evaluation for which ``condition(evaluation)`` is True."""

    def __init__(self, condition: Callable[[dict[str, float]], bool]) -> None:
        self.condition = condition

    def iteration(self, runner: Runner, it: Iteration) -> None:
        if it.evaluation is not None and self.condition(it.evaluation):
            it.stop = True


class Logging(Hook):
    """A row of scalars (``metrics.jsonl``, TensorBoard) every ``log_interval`` iterations,
    after the last and with every evaluation; the agent's histograms (paper Fig. 5: the CPG
    parameters, the feedback's output layer) every ``histogram_interval``."""

    def iteration(self, runner: Runner, it: Iteration) -> None:
        cfg = runner.config
        if not (it.number % cfg.log_interval == 0 or it.last or it.evaluation is not None):
            return
        row = scalars(runner, it)
        if it.evaluation is not None:
            row.update(it.evaluation)
        runner.last_row = row
        runner.run_log.write(runner.iteration, runner.global_step, row)
        if runner.run_log.use_tensorboard and runner.iteration % cfg.histogram_interval == 0:
            runner.run_log.histograms(runner.global_step, runner.agent.log_histograms())

    def end(self, runner: Runner) -> None:
        runner.run_log.flush()


LOSSES = ("policy_loss", "value_loss", "entropy", "approx_kl", "kl", "clipfrac",
          "explained_variance")  # fmt: skip


def scalars(runner: Runner, it: Iteration) -> dict[str, float]:
    """An iteration's row: the recent episodes (return, length, the env's metrics, reward
    terms), PPO's losses and learning rates, the time spent and the agent's own scalars."""
    row = runner.rollout.episodes.scalars()
    row["charts/SPS"] = it.timing["SPS"]
    row["charts/learning_rate"] = it.stats["learning_rate"]
    if "cpg_learning_rate" in it.stats:  # ppo.cpg_learning_rate's group
        row["charts/cpg_learning_rate"] = it.stats["cpg_learning_rate"]
    for key in LOSSES:
        if key in it.stats:
            row[f"losses/{key}"] = it.stats[key]
    for key in ("collection", "simulation", "inference", "learning"):
        row[f"time/{key}"] = it.timing[key]
    row["time/train_wall"] = runner.train_wall
    row.update(runner.agent.log_scalars())  # log-std, CPG parameters, ...
    return row


class Progress(Hook):
    """A rich progress bar on a terminal, a plain line every ``interval`` seconds otherwise:
    steps, SPS, the recent return and env metrics, the last evaluation."""

    def __init__(self, interval: float) -> None:
        self.interval = interval
        self.display: Any = None
        self.task: Any = None

    def start(self, runner: Runner, fresh: bool) -> None:
        cfg = runner.config
        total = cfg.search_steps + cfg.num_iterations * cfg.steps_per_iteration
        self.display, self.task = make_progress(
            cfg.agent, total, runner.global_step, self.interval, _evaluation_text(runner)
        )

    def iteration(self, runner: Runner, it: Iteration) -> None:
        episodes = runner.rollout.episodes
        self.display.update(
            self.task,
            completed=runner.global_step,
            sps=f"{it.timing['SPS']:,.0f}",
            ret=return_text(episodes.mean("return")),
            metrics=metrics_text(episodes.env_metrics()),
            evaluation=_evaluation_text(runner),
        )

    def end(self, runner: Runner) -> None:
        if self.display is not None:
            self.display.stop()
            self.display = None


def _evaluation_text(runner: Runner) -> str:
    return evaluation_text(runner.last_evaluation) if runner.last_evaluation else ""
