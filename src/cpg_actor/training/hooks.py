"""What the training loops call around their iterations: evaluation, logging, the progress
display, checkpoints and any hook of the caller's own (``Runner(hooks=...)``).

:func:`run_loop` is the loop both runners share (PPO's :class:`~cpg_actor.training.runner.
Runner`, the open-loop search's :class:`~cpg_actor.training.es_runner.ESRunner`): it calls
every hook in order, ``start`` before the first iteration, ``iteration`` after each with the
:class:`Iteration` the earlier hooks filled in (the evaluation, a request to stop), ``end``
when the loop returns or raises; ``close`` with the runner. Hooks read the runner (its
``config``, ``run_dir``, ``run_log``, counters, ``last_evaluation``, ``save_checkpoint``) and
change nothing it trains: the evaluation runs on envs of its own and draws no random numbers,
so a run trains the same with or without it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from cpg_actor.training.evaluation import TrainingEvaluation
from cpg_actor.training.progress import evaluation_text, make_progress, metrics_text, return_text

Row = Callable[[Any, "Iteration"], dict[str, Any]]  # (runner, iteration) -> scalars or fields


@dataclass
class Iteration:
    """One iteration (a PPO update, a CMA-ES generation) as the hooks see it."""

    number: int  # iterations done, this one included
    last: bool  # the run's last iteration
    stats: dict[str, float]  # what the algorithm reports (PPO's losses, learning rates, ...)
    timing: dict[str, float]  # SPS and seconds
    evaluation: dict[str, float] | None = None  # the evaluation's row, if it ran
    stop: bool = False  # stop after this iteration (checkpoints save it first)
    extras: dict[str, Any] = field(default_factory=dict)  # the runner's own, for its rows


class Hook:
    """A hook of the training loop; every method does nothing unless overridden."""

    def start(self, runner: Any, fresh: bool) -> None:
        """Before the first iteration; ``fresh``: a new run, not one resumed."""

    def iteration(self, runner: Any, it: Iteration) -> None:
        """After each iteration."""

    def end(self, runner: Any) -> None:
        """When the loop returns or raises."""

    def close(self) -> None:
        """Release what the hook holds (the runner closes)."""


def run_loop(runner: Any, hooks: Sequence[Hook], fresh: bool, more: Callable[[], bool]) -> None:
    """``runner.train_iteration()`` while ``more()``, calling the hooks around it."""
    try:
        for hook in hooks:
            hook.start(runner, fresh)
        while more():
            it = runner.train_iteration()
            for hook in hooks:
                hook.iteration(runner, it)
            if it.stop:
                break
    finally:
        for hook in hooks:
            hook.end(runner)


class Evaluation(Hook):
    """Deterministic episodes every ``eval_interval`` iterations, after the last and before
    the first of a new run (the untrained, warm-started or starting agent, logged alone);
    none with ``eval_interval`` 0 (:class:`~cpg_actor.training.evaluation.TrainingEvaluation`)."""

    def __init__(self, runs: TrainingEvaluation) -> None:
        self.runs = runs

    def start(self, runner: Any, fresh: bool) -> None:
        if fresh and runner.config.eval_interval > 0:
            runner.last_evaluation = evaluation = self.runs()
            row = {**evaluation, "time/train_wall": runner.train_wall}
            runner.run_log.write(runner.iteration, runner.global_step, row)

    def iteration(self, runner: Any, it: Iteration) -> None:
        interval = runner.config.eval_interval
        if interval > 0 and (it.number % interval == 0 or it.last):
            it.evaluation = runner.last_evaluation = self.runs()

    def close(self) -> None:
        self.runs.close()


class StopWhen(Hook):
    """Stop after the first evaluation for which ``condition(evaluation)`` is True."""

    def __init__(self, condition: Callable[[dict[str, float]], bool]) -> None:
        self.condition = condition

    def iteration(self, runner: Any, it: Iteration) -> None:
        if it.evaluation is not None and self.condition(it.evaluation):
            it.stop = True


class Logging(Hook):
    """A row of scalars, ``row(runner, it)`` (``metrics.jsonl``, TensorBoard), every
    ``log_interval`` iterations, after the last and with every evaluation; the agent's
    histograms (paper Fig. 5: the CPG parameters, the feedback's output layer) every
    ``histogram_interval``."""

    def __init__(self, row: Row) -> None:
        self.row = row

    def iteration(self, runner: Any, it: Iteration) -> None:
        cfg = runner.config
        if not (it.number % cfg.log_interval == 0 or it.last or it.evaluation is not None):
            return
        row = self.row(runner, it)
        if it.evaluation is not None:
            row.update(it.evaluation)
        runner.last_row = row
        runner.run_log.write(runner.iteration, runner.global_step, row)
        if runner.run_log.use_tensorboard and runner.iteration % cfg.histogram_interval == 0:
            runner.run_log.histograms(runner.global_step, runner.agent.log_histograms())

    def end(self, runner: Any) -> None:
        runner.run_log.flush()


class Progress(Hook):
    """A rich progress bar on a terminal, a plain line every ``interval`` seconds otherwise:
    steps of ``runner.planned_steps``, the ``fields(runner, it)`` (``sps``, ``ret``,
    ``metrics``) and the last evaluation."""

    def __init__(self, interval: float, fields: Row) -> None:
        self.interval = interval
        self.fields = fields
        self.display: Any = None
        self.task: Any = None

    def start(self, runner: Any, fresh: bool) -> None:
        self.display, self.task = make_progress(
            runner.config.agent,
            runner.planned_steps,
            runner.global_step,
            self.interval,
            _evaluation_text(runner),
        )

    def iteration(self, runner: Any, it: Iteration) -> None:
        self.display.update(
            self.task,
            completed=runner.global_step,
            **self.fields(runner, it),
            evaluation=_evaluation_text(runner),
        )

    def end(self, runner: Any) -> None:
        if self.display is not None:
            self.display.stop()
            self.display = None


def _evaluation_text(runner: Any) -> str:
    return evaluation_text(runner.last_evaluation) if runner.last_evaluation else ""


def loop_hooks(
    evaluation: TrainingEvaluation,
    row: Row,
    progress_fields: Row,
    progress: bool,
    progress_interval: float,
) -> list[Hook]:
    """The hooks a runner calls first, in order: the evaluation, the logging of ``row``'s
    scalars and, with ``progress``, the progress display of ``progress_fields`` every
    ``progress_interval`` seconds (off a terminal)."""
    display = [Progress(progress_interval, progress_fields)] if progress else []
    return [Evaluation(evaluation), Logging(row), *display]


class Checkpoints(Hook):
    """``runner.save_checkpoint()`` every ``checkpoint_interval`` iterations, after the last,
    when a hook stops the run, and before the first iteration of a new run (the untrained or
    starting agent: a "before"); nothing without a run directory. The loop calls it after
    every other hook, so that it saves what they decided."""

    def start(self, runner: Any, fresh: bool) -> None:
        if fresh and runner.run_dir is not None:
            runner.save_checkpoint()

    def iteration(self, runner: Any, it: Iteration) -> None:
        at_interval = it.number % runner.config.checkpoint_interval == 0
        if runner.run_dir is not None and (at_interval or it.last or it.stop):
            runner.save_checkpoint()


# -- PPO's rows ---------------------------------------------------------------------------------
LOSSES = ("policy_loss", "value_loss", "entropy", "approx_kl", "kl", "clipfrac",
          "explained_variance")  # fmt: skip


def ppo_row(runner: Any, it: Iteration) -> dict[str, float]:
    """A PPO iteration's row: the recent episodes (return, length, the env's metrics, reward
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


def ppo_progress(runner: Any, it: Iteration) -> dict[str, str]:
    """The progress display's fields of a PPO iteration."""
    episodes = runner.rollout.episodes
    return {
        "sps": f"{it.timing['SPS']:,.0f}",
        "ret": return_text(episodes.mean("return")),
        "metrics": metrics_text(episodes.env_metrics()),
    }
