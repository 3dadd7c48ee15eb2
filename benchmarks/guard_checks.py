"""Training with and without dynamo's guard checks before each compiled call
(``ppo.skip_guard_checks``, ``cpg_actor.training.compile_stance``), taking turns in one process.

One compiled runner (default: the throughput preset's ``cpg-actor``) makes a warm-up
iteration, then ``--pairs`` pairs of blocks of ``--iterations`` iterations, one block with the
checks skipped and one with them made at every call, the order alternating from pair to pair.
A machine whose speed drifts slows both blocks of a pair alike, so the figure is the median of
the pairs' speed-ups (skipped over checked), with their range. The runner trains on throughout:
both settings run the same compiled code, so the blocks differ only in the checks.

    python benchmarks/guard_checks.py [--agent cpg-actor] [--preset throughput] [--pairs 8]
        [--iterations 3] [--output benchmarks/results/guard_checks.md]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

from cpg_actor.machine import brief_openmp_spinning

brief_openmp_spinning(os.environ)  # as `cpg-actor train` does, before torch loads

import torch  # noqa: E402

from bench_report import measured, write  # noqa: E402
from cpg_actor.machine import cpu_model, load_average, usable_cores  # noqa: E402
from cpg_actor.training.runner import Runner  # noqa: E402
from train_throughput import make_config  # noqa: E402


def block_sps(runner: Runner, iterations: int, skip: bool) -> float:
    """Control steps per second of ``iterations`` iterations, guard checks skipped or not."""
    runner.config.ppo.skip_guard_checks = skip
    start = time.perf_counter()
    for _ in range(iterations):
        runner.collect()
        runner.update()
    return iterations * runner.config.steps_per_iteration / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--agent", default="cpg-actor")
    parser.add_argument("--preset", default="throughput")
    parser.add_argument("--pairs", type=int, default=8)
    parser.add_argument("--iterations", type=int, default=3, help="iterations per block")
    parser.add_argument("--output", default="benchmarks/results/guard_checks.md")
    args = parser.parse_args()
    if args.pairs < 1 or args.iterations < 1:
        parser.error("--pairs and --iterations must be at least 1")
    config = make_config(args.agent, args.preset, compile=True)
    config.total_steps = (1 + 2 * args.pairs * args.iterations) * config.steps_per_iteration
    runner = Runner(config, run_dir=None, tensorboard=False)
    try:
        runner.start_episodes()
        runner.collect()  # the warm-up: every compiled function built, its guards checked
        runner.update()
        if not runner.compile_stance.skips_guard_checks:
            raise SystemExit("the runner does not skip guard checks (not compiled on the CPU?)")
        skipped, checked = [], []
        for pair in range(args.pairs):
            order = (True, False) if pair % 2 == 0 else (False, True)
            for skip in order:
                (skipped if skip else checked).append(block_sps(runner, args.iterations, skip))
    finally:
        runner.close()
    ratios = [s / c for s, c in zip(skipped, checked, strict=True)]
    command = (
        f"python benchmarks/guard_checks.py --agent {args.agent} --preset {args.preset} "
        f"--pairs {args.pairs} --iterations {args.iterations}"
    )
    lines = [
        "# Compiled calls with and without dynamo's guard checks",
        "",
        measured(command) + ".",
        "",
        f"Machine: {cpu_model()}, {usable_cores()} usable cores (load {load_average()}), torch "
        f"{torch.__version__}; {args.agent}, {args.preset} preset, compiled, "
        f"{config.num_envs} envs; blocks of {args.iterations} iterations "
        f"({args.iterations * config.steps_per_iteration:,} control steps) taking turns.",
        "",
        "| pair | guard checks skipped, SPS | checked at every call, SPS | speed-up |",
        "| ---: | ---: | ---: | ---: |",
    ]
    for i, (s, c, r) in enumerate(zip(skipped, checked, ratios, strict=True), 1):
        lines.append(f"| {i} | {s:,.0f} | {c:,.0f} | {r:.3f}x |")
    lines += [
        "",
        f"Median speed-up {statistics.median(ratios):.3f}x (range {min(ratios):.3f}-"
        f"{max(ratios):.3f}) over {args.pairs} pairs; median SPS {statistics.median(skipped):,.0f} "
        f"skipped, {statistics.median(checked):,.0f} checked.",
        "",
    ]
    write(args.output, lines)


if __name__ == "__main__":
    main()
