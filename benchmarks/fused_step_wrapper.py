"""The fused PPO step's kernels called from C++ (inductor's ``cpp_wrapper``) or from Python,
in one process: two runners of the same settings, one each way, take turns iteration by
iteration, so a slow spell of a shared machine hits both alike.

    python benchmarks/fused_step_wrapper.py [--presets paper throughput]
        [--agents cpg-actor mlp] [--pairs 6]
        [--output benchmarks/results/fused_step_wrapper.md]

Per preset and agent: the median collection cost per control step, PPO update cost per
sample and training steps per second of each runner, and the median of the paired ratios
(Python wrapper over C++ wrapper, each pair measured back to back). Which runner goes first
alternates between pairs: the second of two runners in one process collects a few per cent
slower, whichever it is. Both give the same parameters bit for bit
(``tests/ppo/test_train_step.py``).
"""

from __future__ import annotations

import argparse
import datetime
import statistics
import time
from pathlib import Path

import torch

import cpg_actor.ppo.algorithm as algorithm
from cpg_actor.machine import cpu_model, git_commit, load_average, usable_cores
from cpg_actor.runner import Runner
from train_throughput import make_config


def make_runner(agent: str, preset: str, cpp_wrapper: bool) -> Runner:
    headers = algorithm.python_headers
    algorithm.python_headers = lambda: cpp_wrapper  # what PPO asks when it builds the step
    try:
        config = make_config(agent, preset, compile=True)
        config.total_steps = 10**12  # never reached: the linear schedule stays put
        runner = Runner(config, run_dir=None, tensorboard=False)
    finally:
        algorithm.python_headers = headers
    if runner.ppo.fused_step is None or runner.ppo.fused_step.cpp_wrapper != cpp_wrapper:
        raise RuntimeError("the fused step was not built as asked (no C++ compiler?)")
    runner.start_episodes()
    return runner


def iteration(runner: Runner) -> dict[str, float]:
    samples = runner.config.steps_per_iteration
    start = time.perf_counter()
    runner.collect()
    collected = time.perf_counter()
    runner.update()
    end = time.perf_counter()
    return {
        "collect_us": 1e6 * (collected - start) / samples,
        "update_us": 1e6 * (end - collected) / samples,
        "SPS": samples / (end - start),
    }


def compare(agent: str, preset: str, pairs: int) -> dict[str, dict[str, list[float]]]:
    runners = {"python": make_runner(agent, preset, False), "cpp": make_runner(agent, preset, True)}
    try:
        for _ in range(2):  # compiles and warm-up
            for runner in runners.values():
                iteration(runner)
        results: dict[str, dict[str, list[float]]] = {name: {} for name in runners}
        for pair in range(pairs):
            order = list(runners) if pair % 2 == 0 else list(reversed(runners))
            for name in order:
                for key, value in iteration(runners[name]).items():
                    results[name].setdefault(key, []).append(value)
        return results
    finally:
        for runner in runners.values():
            runner.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="+", default=["paper", "throughput"])
    parser.add_argument("--agents", nargs="+", default=["cpg-actor", "mlp"])
    parser.add_argument("--pairs", type=int, default=6)
    parser.add_argument("--output", default="benchmarks/results/fused_step_wrapper.md")
    args = parser.parse_args()
    if args.pairs < 1:
        parser.error(f"--pairs must be >= 1, got {args.pairs}")
    if not algorithm.python_headers():
        parser.error("Python's C headers (Python.h) are missing: no cpp_wrapper to compare")
    torch.set_num_threads(1)
    median = statistics.median
    lines = [
        "# The fused PPO step: kernels called from C++ or from Python",
        "",
        f"Measured {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC at commit "
        f"{git_commit() or 'unknown'} with `python benchmarks/fused_step_wrapper.py --presets "
        f"{' '.join(args.presets)} --agents {' '.join(args.agents)} --pairs {args.pairs}` on "
        f"{cpu_model()}, {usable_cores()} usable cores (load {load_average()}), torch "
        f"{torch.__version__}. Medians over {args.pairs} pairs of iterations; a speed-up is the "
        "median of the paired ratios (Python over C++), its range in brackets.",
        "",
        "| preset | agent | update us/sample, C++ (Python) | update speed-up | collection "
        "us/step, C++ (Python) | training SPS, C++ (Python) | training speed-up |",
        "| --- | --- | ---: | ---: | ---: | ---: | ---: |",
    ]
    for preset in args.presets:
        for agent in args.agents:
            r = compare(agent, preset, args.pairs)
            cpp, py = r["cpp"], r["python"]
            update = [p / c for p, c in zip(py["update_us"], cpp["update_us"], strict=True)]
            sps = [c / p for p, c in zip(py["SPS"], cpp["SPS"], strict=True)]
            row = (
                f"| {preset} | {agent} | {median(cpp['update_us']):.1f} "
                f"({median(py['update_us']):.1f}) | {median(update):.2f}x "
                f"({min(update):.2f}-{max(update):.2f}) | {median(cpp['collect_us']):.1f} "
                f"({median(py['collect_us']):.1f}) | {median(cpp['SPS']):,.0f} "
                f"({median(py['SPS']):,.0f}) | {median(sps):.2f}x ({min(sps):.2f}-{max(sps):.2f}) |"
            )
            print(row, flush=True)
            lines.append(row)
    lines += [
        "",
        "Collection does not involve the fused step: its differences are the noise of the machine.",
        "",
    ]
    output = Path(args.output)
    output.parent.mkdir(parents=True, exist_ok=True)
    tmp = output.with_suffix(".tmp")
    tmp.write_text("\n".join(lines))
    tmp.replace(output)
    print(f"written {output}")


if __name__ == "__main__":
    main()
