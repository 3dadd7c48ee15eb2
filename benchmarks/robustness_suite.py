"""The robustness suite's cost: ``cpg-actor robustness`` on a reproduction's runs, with the
eval-only cost (each run's nominal evaluation alone) next to it.

The target (issue "Beyond the paper: a robustness suite"): the whole suite for 3 variants x 5
seeds on the hopper in at most 15 minutes on 2 cores. This times the suite run by run
(``cpg_actor.robustness.suite.evaluate_run``, the command's own loop, writing nothing) and a
nominal evaluation of each run alone, and projects both to 3 x 5 runs::

    python benchmarks/robustness_suite.py results/decisive-2M --variants cpg-actor,mlp,cho2019-warm
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

TARGET_RUNS = 15  # 3 variants x 5 seeds
TARGET_SECONDS = 15 * 60


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("results", help="a reproduction directory (cpg-actor reproduce's)")
    parser.add_argument("--variants", default="cpg-actor,mlp,cho2019-warm")
    parser.add_argument("--seeds", type=int, default=5, help="seeds per variant at most")
    parser.add_argument("--episodes", type=int, default=4, help="the command's default")
    parser.add_argument("--output", default="benchmarks/results/robustness_suite.md")
    args = parser.parse_args(argv)

    from cpg_actor.machine import brief_openmp_spinning

    brief_openmp_spinning(os.environ)
    from cpg_actor.config import TrainConfig
    from cpg_actor.deploy import load_policy
    from cpg_actor.machine import cpu_model, usable_cores
    from cpg_actor.robots.registry import get_robot
    from cpg_actor.robustness.runs import CHECKPOINT, find_runs
    from cpg_actor.robustness.suite import evaluate_run
    from cpg_actor.training.evaluation import evaluate_policy

    wanted = args.variants.split(",")
    runs = [run for run in find_runs([args.results]) if run.variant in wanted]
    runs = [run for run in runs if sorted(r.seed for r in runs if r.variant == run.variant
                                          ).index(run.seed) < args.seeds]  # fmt: skip
    if not runs:
        raise SystemExit(f"no runs of {args.variants} in {args.results}")
    table = get_robot(runs[0].robot).perturbations
    names = list(table.axes)
    evaluations = 1 + sum(len(axis.levels) for axis in table.axes.values())
    rows, suite_total, eval_total = [], 0.0, 0.0
    for run in runs:
        config = TrainConfig.load(run.path / "config.yaml")
        start = time.perf_counter()
        policy = load_policy(run.path / CHECKPOINT, run_config=config)
        evaluate_policy(policy, config, args.episodes, seed=1000)
        alone = time.perf_counter() - start
        start = time.perf_counter()
        evaluate_run(run, names, args.episodes, 1000, progress=lambda line: None)
        suite = time.perf_counter() - start
        rows.append(f"| {run.variant} | {run.seed} | {suite:.1f} | {alone:.1f} |")
        print(rows[-1], flush=True)
        suite_total, eval_total = suite_total + suite, eval_total + alone
    scale = TARGET_RUNS / len(runs)
    lines = [
        "# The robustness suite's cost",
        "",
        f"`python benchmarks/robustness_suite.py {args.results} --variants {args.variants}`: "
        f"{len(runs)} runs, {args.episodes} episodes per level, {evaluations} evaluations per "
        f"run (nominal and {len(names)} perturbations at their levels).",
        "",
        f"- CPU: {cpu_model()}, {usable_cores()} usable logical core(s); Python "
        f"{platform.python_version()}",
        "",
        "| variant | seed | suite (s) | eval only (s) |",
        "| --- | --- | --- | --- |",
        *rows,
        "",
        f"Suite: {suite_total:.0f} s for {len(runs)} runs, {suite_total * scale / 60:.1f} min "
        f"for 3 x 5 (target {TARGET_SECONDS // 60} min); eval only: {eval_total:.0f} s, "
        f"{eval_total * scale / 60:.1f} min for 3 x 5.",
        "",
    ]
    Path(args.output).write_text("\n".join(lines))
    print("\n".join(lines[-2:]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
