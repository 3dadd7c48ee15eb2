"""What the benchmark scripts share: the provenance line, the write of their Markdown
results and the check of the files they write beside it, running a script with the package of
another source tree, and the record of a training run's evaluations (the time-to-a-target
benchmarks)."""

from __future__ import annotations

import argparse
import datetime
import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from cpg_actor.machine import git_commit


def measured(command: str) -> str:
    """``Measured <UTC time> at commit <commit> with `command```."""
    now = datetime.datetime.now(datetime.timezone.utc)
    return f"Measured {now:%Y-%m-%d %H:%M} UTC at commit {git_commit()} with `{command}`"


def write(path: str | Path, lines: list[str]) -> None:
    """Write ``lines`` to ``path`` atomically (its folder made if needed) and print them."""
    from cpg_actor.files import atomic_write_text

    atomic_write_text("\n".join(lines), Path(path))
    print("\n".join(lines))


def companions(
    parser: argparse.ArgumentParser, output: str | Path, suffixes: tuple[str, ...],
    named: bool, overwrite: bool,
) -> list[Path]:  # fmt: skip
    """The files a benchmark writes beside its report ``output``: its name with each of
    ``suffixes`` (".json", ".png"). Beside a report the user ``named`` (``--output``), a file
    of such a name may be the user's own: one that exists is refused (``parser.error``, one
    line, before anything runs) unless ``overwrite``. Beside the default report they are the
    benchmark's own results (benchmarks/results) and are replaced."""
    output = Path(output)
    paths = [output.with_suffix(suffix) for suffix in suffixes]
    if output in paths:
        parser.error(f"--output {output}: the report would be its own {output.suffix} file; "
                     "give a report name ending in .md")  # fmt: skip
    existing = [str(path) for path in paths if path.exists() or path.is_symlink()]
    if named and existing and not overwrite:
        parser.error(f"--output {output}: {', '.join(existing)} exists and would be replaced "
                     "by the file written beside the report; pass --overwrite to replace it, "
                     "or choose another --output")  # fmt: skip
    return paths


def json_from_tree(src: str | Path, arguments: list[str], show_stderr: bool = False) -> dict:
    """``python *arguments`` with the ``cpg_actor`` package in ``src`` first on its path; the
    last line it prints, parsed as JSON. RuntimeError with the end of its stderr if it fails.
    ``show_stderr``: its stderr goes to ours as it comes (a long run's progress)."""
    path = os.pathsep.join([str(src), os.environ.get("PYTHONPATH", "")])
    done = subprocess.run(
        [sys.executable, *arguments],
        env=dict(os.environ, PYTHONPATH=path),
        stdout=subprocess.PIPE,
        stderr=None if show_stderr else subprocess.PIPE,
        text=True,
    )
    if done.returncode != 0:
        said = "its stderr above" if show_stderr else done.stderr[-3000:]
        raise RuntimeError(f"{' '.join(arguments)} with the package in {src} failed:\n{said}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def evaluation_recorder(stop: Callable[[dict[str, float]], bool] | None = None):
    """A training-loop hook (:class:`cpg_actor.training.hooks.Hook`, for ``Runner(hooks=...)``)
    that records every evaluation of a run in its ``history``, as ``(env steps, training wall
    time, evaluation)`` at it: the one before the first update (at 0 s; an agent that starts
    from a gait or a warm start may already be there) and the periodic ones. With ``stop``, the
    run stops after the first iteration by which an evaluation met it (a first evaluation
    that met it stops the run after one iteration, still recorded at its 0 s). It reads the
    runner and changes nothing it trains."""
    from cpg_actor.training.hooks import Hook

    class Recorder(Hook):
        def __init__(self) -> None:
            self.history: list[tuple[int, float, dict[str, float]]] = []
            self.met = False

        def add(self, runner, evaluation: dict[str, float]) -> None:
            self.history.append((runner.global_step, runner.train_wall, dict(evaluation)))
            self.met = self.met or (stop is not None and bool(stop(evaluation)))

        def start(self, runner, fresh: bool) -> None:
            if runner.last_evaluation is not None:  # the evaluation hook's, before the first
                self.add(runner, runner.last_evaluation)

        def iteration(self, runner, it) -> None:
            if it.evaluation is not None:
                self.add(runner, it.evaluation)
            it.stop = it.stop or self.met

    return Recorder()


def charged_warm_start(runner, config) -> dict:
    """What ``runner``'s warm start costs, charged to it: ``{"steps", "wall"}``, 0 for an agent
    without one. Its env steps (``warm_start.rollout_steps`` control steps on each of
    ``num_envs`` envs) are known now; its wall time fills in as :meth:`Runner.learn` runs it
    (``run_warm_start`` is wrapped in a timer)."""
    import time

    cost = {"steps": 0, "wall": 0.0}
    if runner.spec.warm_start is None:
        return cost
    fit = runner.run_warm_start

    def timed_warm_start() -> list[float]:
        begin = time.perf_counter()
        try:
            return fit()
        finally:
            cost["wall"] += time.perf_counter() - begin

    runner.run_warm_start = timed_warm_start  # what learn() calls before PPO
    cost["steps"] = config.warm_start.rollout_steps * config.num_envs
    return cost
