"""Progress display of a training run: a rich progress bar on a terminal, a plain line every
``interval`` seconds otherwise (a log file, a cluster job).

The first iteration of a run (or of a resumed run) includes torch.compile's compilation and
the first calls' set-up, so no ETA is shown until a second one has finished; the ETA then
comes from the iterations after the first only (the rich bar's rate leaves out the first
update too). Before the first finished episode the return shows as ``-``."""

from __future__ import annotations

import math
import sys
import time
from typing import Any

NOT_ENV_METRICS = ("return", "return_min", "length")  # eval/ keys that are the runner's own


def metrics_text(metrics: dict[str, float]) -> str:
    """``"hop_height 0.312"``: an env's episode metrics (name -> value) for the display."""
    return " ".join(f"{name} {value:.3f}" for name, value in metrics.items())


def evaluation_text(evaluation: dict[str, float]) -> str:
    """One evaluation for the progress display: its return and the env's episode metrics."""
    env_metrics = {
        key.removeprefix("eval/"): value
        for key, value in evaluation.items()
        if key.startswith("eval/") and key.removeprefix("eval/") not in NOT_ENV_METRICS
    }
    return " ".join(filter(None, [f"eval return {evaluation['eval/return']:.1f}",
                                  metrics_text(env_metrics)]))  # fmt: skip


class PlainProgress:
    """Progress as a plain line every ``interval`` seconds (and at the end) when stdout is not a
    terminal; the same ``update``/``stop`` calls as the rich progress bar."""

    def __init__(self, name: str, total: int, completed: int, interval: float) -> None:
        self.name, self.total, self.interval = name, total, interval
        self.start = self.last = time.perf_counter()
        # (time, steps) at the end of the first iteration (compilation, warm-up): the ETA's start
        self.warm: tuple[float, int] | None = None
        self.fields: dict[str, Any] = {"completed": completed, "evaluation": ""}

    def update(self, task: Any, **fields: Any) -> None:
        self.fields.update(fields)
        now = time.perf_counter()
        if self.warm is None:
            self.warm = (now, self.fields["completed"])
        if now - self.last >= self.interval or self.fields["completed"] >= self.total:
            self.last = now
            self.print(now)

    def print(self, now: float) -> None:
        done = self.fields["completed"]
        elapsed = now - self.start
        print(
            f"[train {self.name}] {done:,}/{self.total:,} steps ({100 * done / self.total:.1f}%), "
            f"{self.fields.get('sps', '-')} SPS, elapsed {elapsed:.0f} s, {self.eta(now, done)}, "
            f"return {self.fields.get('ret', '-')} {self.fields.get('metrics', '')} "
            f"{self.fields['evaluation']}".replace("  ", " ").rstrip(),
            flush=True,
        )

    def eta(self, now: float, done: int) -> str:
        """``"ETA 290 s"`` from the rate since the first iteration; before a second one has
        finished, ``"ETA after warm-up"``."""
        if done >= self.total:
            return "ETA 0 s"
        if self.warm is None or done <= self.warm[1] or now <= self.warm[0]:
            return "ETA after warm-up"
        rate = (done - self.warm[1]) / (now - self.warm[0])
        return f"ETA {(self.total - done) / rate:.0f} s"

    def stop(self) -> None:
        pass


def return_text(value: float) -> str:
    """The mean episode return for the display; ``-`` before an episode has finished."""
    return f"{value:.2f}" if math.isfinite(value) else "-"


def make_progress(name: str, total: int, completed: int, interval: float, evaluation: str):
    """``(progress, task)``: a started rich progress bar (stdout a terminal) or a
    :class:`PlainProgress`; both take ``update(task, completed=, sps=, ret=, metrics=,
    evaluation=)`` and ``stop()`` (``metrics``: :func:`metrics_text` of the env's metrics)."""
    if not sys.stdout.isatty():
        return PlainProgress(name, total, completed, interval), None
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    progress = Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(bar_width=16),
        MofNCompleteColumn(),
        TextColumn("steps {task.fields[sps]} SPS"),
        TimeElapsedColumn(),
        TextColumn("ETA"),
        TimeRemainingColumn(),
        TextColumn("return {task.fields[ret]} {task.fields[metrics]}"),
        TextColumn("{task.fields[evaluation]}"),
    )
    task = progress.add_task(
        name, total=total, completed=completed, sps="-", ret="-", metrics="", evaluation=evaluation
    )
    progress.start()
    return progress, task
