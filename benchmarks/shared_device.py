"""Runs sharing one machine: the combined training rate of K ``cpg-actor train`` processes.

    python benchmarks/shared_device.py [--runs 1 2 4] [--preset gpu] [--agent cpg-actor]
        [--seconds 150] [--train-args="--num-envs 4096"]
        [--output benchmarks/results/shared_device.md]

The paper's budget is 25 runs (5 variants x 5 seeds x 20M steps). ``cpg-actor reproduce
--workers K`` trains K of them at a time as separate processes on one GPU (or CPU); what K buys
depends on how much of the device one run leaves idle. For each K this starts K ``cpg-actor
train`` processes together (seeds 0..K-1, the preset's settings plus ``--train-args``), each
with its share of the cores for its simulator and update threads and one torch thread for its
rollout, as ``reproduce`` starts them (``--automatic-threads``: the runs' own automatic
threads, every usable core each, as runs started by hand get), watches their ``metrics.jsonl``
(a row per iteration, stamped with the time this script saw it) for ``--seconds``, longer
where a run has not yet finished the 3 iterations a window needs (a busy or slow machine; up to
``WAIT_FACTOR`` times ``--seconds``), then stops them. Each run's rate is taken over the
window in which every run was past its second iteration (start-up, JIT and ``torch.compile``
excluded): its control steps in the window over the window's wall time, evaluations and
checkpoints included, as a user waits for them. The combined rate is their sum, and the
paper's budget is given at it. K = 1 is the reference, measured in the same run.
"""

from __future__ import annotations

import argparse
import os
import shlex
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_report import measured, write
from cpg_actor.machine import cpu_model, load_average, usable_cores
from cpg_actor_studies.reproduction.plan import thread_shares

PAPER_BUDGET = 5 * 5 * 20_000_000  # control steps: 5 variants x 5 seeds x 20M
POLL_S = 0.25
NEEDED = 3  # iterations per run: 2 of start-up, then the window
WAIT_FACTOR = 10  # the longest wait for them, in multiples of --seconds


def read_rows(path: Path, seen: int) -> list[str]:
    """The complete lines of ``path`` after the first ``seen`` ones."""
    if not path.exists():
        return []
    lines = path.read_text().split("\n")[:-1]  # the last piece is "" or an unfinished line
    return lines[seen:]


def watch(commands: list[list[str]], run_dirs: list[Path], seconds: float) -> list[list]:
    """Start the processes, stamp each new metrics row with the time it appeared, stop them
    after ``seconds`` once every run has ``NEEDED`` iterations (at most ``WAIT_FACTOR`` times
    ``seconds``), or when all have ended; per run: [(time, global_step), ...]."""
    import json

    logs = [open(d.parent / f"{d.name}.log", "w") for d in run_dirs]  # noqa: SIM115
    processes = [
        subprocess.Popen(c, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        for c, log in zip(commands, logs, strict=True)
    ]
    stamps: list[list] = [[] for _ in run_dirs]
    seen = [0] * len(run_dirs)
    begun = time.monotonic()

    def going_on() -> bool:
        elapsed = time.monotonic() - begun
        short = any(len(s) < NEEDED for s in stamps)
        return elapsed < seconds or (short and elapsed < WAIT_FACTOR * seconds)

    try:
        while going_on() and any(p.poll() is None for p in processes):
            time.sleep(POLL_S)
            now = time.monotonic()
            for i, run_dir in enumerate(run_dirs):
                for line in read_rows(run_dir / "metrics.jsonl", seen[i]):
                    seen[i] += 1
                    row = json.loads(line)
                    if "charts/SPS" in row:  # a training iteration (not the step-0 evaluation)
                        stamps[i].append((now, int(row["global_step"])))
    finally:
        for process in processes:
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGTERM)
        for process in processes:
            process.wait()
        for log in logs:
            log.close()
    for i, process in enumerate(processes):
        if process.returncode not in (0, -signal.SIGTERM) and len(stamps[i]) < NEEDED:
            log = (run_dirs[i].parent / f"{run_dirs[i].name}.log").read_text()
            raise RuntimeError(f"run {i} failed (exit {process.returncode}):\n{log[-3000:]}")
    return stamps


def window_rates(stamps: list[list]) -> tuple[list[float], float]:
    """Each run's control steps per second over the window where all were past their second
    iteration, and the window's length (s); ValueError if the runs never overlapped so."""
    if any(len(s) < NEEDED for s in stamps):
        raise ValueError(
            f"a run did not finish {NEEDED} iterations in the time given; raise --seconds "
            f"(iterations seen: {[len(s) for s in stamps]})"
        )
    start = max(s[1][0] for s in stamps)  # every run has finished its second iteration
    end = min(s[-1][0] for s in stamps)  # before any run stopped
    rates = []
    for s in stamps:
        inside = [(t, step) for t, step in s if start <= t <= end]
        if len(inside) < 2:
            raise ValueError("the runs' steady iterations did not overlap; raise --seconds")
        (t0, s0), (t1, s1) = inside[0], inside[-1]
        rates.append((s1 - s0) / (t1 - t0))
    return rates, end - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", nargs="+", type=int, default=[1, 2, 4])
    parser.add_argument("--preset", default="gpu")
    parser.add_argument("--agent", default="cpg-actor")
    parser.add_argument("--seconds", type=float, default=150.0)
    parser.add_argument("--train-args", default="", help="more `cpg-actor train` flags")
    parser.add_argument(
        "--automatic-threads",
        action="store_true",
        help="the runs' own thread defaults (every usable core each), not reproduce's shares",
    )
    parser.add_argument(
        "--output", default=str(Path(__file__).parent / "results" / "shared_device.md")
    )
    args = parser.parse_args()
    # stopped from outside (`timeout`): stop the training processes too (watch's finally)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(128 + signal.SIGTERM))
    if any(k < 1 for k in args.runs):
        parser.error(f"--runs takes positive integers, got {args.runs}")
    if not args.seconds > 0:
        parser.error(f"--seconds must be a positive number of seconds, got {args.seconds:g}")
    extra = shlex.split(args.train_args)
    command = (
        f"python benchmarks/shared_device.py --runs {' '.join(map(str, args.runs))} "
        f"--preset {args.preset} --agent {args.agent} --seconds {args.seconds:g}"
        + (f" --train-args={shlex.quote(args.train_args)}" if args.train_args else "")
        + (" --automatic-threads" if args.automatic_threads else "")
    )
    threads = (
        "each run's automatic threads"
        if args.automatic_threads
        else (
            "each run's share of the cores for its simulator and update threads, as `reproduce "
            "--workers K` gives them (`--set env_threads=T --set update_threads=T --set "
            "torch_threads=1`, T = cores // K)"
        )
    )
    rows = []
    for k in args.runs:
        with tempfile.TemporaryDirectory(prefix="shared-device-") as tmp:
            run_dirs = [Path(tmp) / f"seed{seed}" for seed in range(k)]
            shares = [] if args.automatic_threads else [
                arg for key, n in thread_shares(k).items() for arg in ("--set", f"{key}={n}")
            ]  # fmt: skip
            commands = [
                [sys.executable, "-m", "cpg_actor.cli", "train", "--preset", args.preset,
                 "--agent", args.agent, "--seed", str(seed), "--total-steps", "1e11",
                 "--run-dir", str(run_dir), "--no-progress", *shares, *extra]
                for seed, run_dir in enumerate(run_dirs)
            ]  # fmt: skip
            rates, window = window_rates(watch(commands, run_dirs, args.seconds))
        combined = sum(rates)
        rows.append((k, rates, window, combined))
        print(f"{k} run(s): {combined:,.0f} control steps/s together over {window:.0f} s")
        reference = rows[0][3]
        lines = [
            "# Runs sharing one machine",
            "",
            f"{measured(command)}, {cpu_model()}, {usable_cores()} usable cores (load "
            f"{load_average()}). `cpg-actor train --preset {args.preset} --agent {args.agent}`"
            + (f" `{args.train_args}`" if args.train_args else "")
            + f", K processes started together (seeds 0..K-1), {threads}; rates over the "
            "window in which every run was past its second iteration, evaluations included.",
            "",
            "| runs | window (s) | each run (control steps/s) | together | "
            f"x {rows[0][0]} run(s) | paper's budget (500M steps) |",
            "| ---: | ---: | --- | ---: | ---: | ---: |",
        ]
        for runs, each, span, total in rows:
            lines.append(
                f"| {runs} | {span:.0f} | {', '.join(f'{r:,.0f}' for r in each)} | "
                f"{total:,.0f} | {total / reference:.2f} | {PAPER_BUDGET / total / 3600:.2f} h |"
            )
        write(args.output, [*lines, ""])  # after each K: a run cut short keeps its rows


if __name__ == "__main__":
    main()
