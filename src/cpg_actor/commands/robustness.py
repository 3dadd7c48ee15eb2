"""`cpg-actor robustness`: trained policies under their robot's perturbations (pushes, payload,
ground friction, latency, sensor noise, motor strength); ``docs/robustness.md``."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

HELP = "evaluate trained runs under perturbations (pushes, payload, friction, latency, ...)"
EPISODES = 4  # per level: the suite's whole grid stays a matter of minutes


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("runs", nargs="+", metavar="RUN",
                        help="a run directory (`cpg-actor train`) or a reproduction directory "
                        "(`cpg-actor reproduce`: every run, grouped by variant)")  # fmt: skip
    parser.add_argument("--out", required=True, help="directory for robustness.json, "
                        "robustness.md and a figure per perturbation")  # fmt: skip
    parser.add_argument(
        "--episodes",
        type=int,
        default=EPISODES,
        help=f"episodes per level, run in parallel (default {EPISODES})",
    )
    parser.add_argument("--perturbations", default=None,
                        help="comma-separated names of the robot's perturbations (default all: "
                        "the hopper's push_up, push_down, payload, friction, latency, obs_noise, "
                        "motor_strength)")  # fmt: skip
    parser.add_argument("--seed", type=int, default=1000, help="environment seed (default 1000)")
    parser.add_argument(
        "--overwrite", action="store_true", help="replace the suite's files already in --out"
    )


def run(args: argparse.Namespace) -> int:
    from cpg_actor.config import MAX_EPISODES, check_count, check_seed
    from cpg_actor.files import check_directory_path
    from cpg_actor.robots.registry import get_robot
    from cpg_actor.robustness.runs import find_runs
    from cpg_actor.robustness.suite import evaluate_run
    from cpg_actor.robustness.summary import outputs, summarise, verdicts, write_outputs

    check_seed(args.seed)
    check_count(args.episodes, "--episodes", MAX_EPISODES)
    out = Path(args.out)
    check_directory_path(out, "--out")  # before the suite, not after it
    runs = find_runs(args.runs)
    robot = get_robot(runs[0].robot)
    table = robot.perturbations
    if table is None:
        raise ValueError(f"the {robot.name} declares no perturbations")
    names = list(table.axes)
    if args.perturbations:
        names = [name.strip() for name in args.perturbations.split(",") if name.strip()]
        unknown = [name for name in names if name not in table.axes]
        if unknown or not names:
            raise ValueError(f"--perturbations: unknown {', '.join(unknown) or '(none given)'}; "
                             f"the {robot.name}'s are {', '.join(table.axes)}")  # fmt: skip
    existing = [path for path in outputs(out, names) if path.exists()]
    if existing and not args.overwrite:
        raise FileExistsError(f"{existing[0]} exists; pass --overwrite to replace the suite's "
                              "files")  # fmt: skip
    start = time.perf_counter()
    results = []
    for i, run_ref in enumerate(runs, 1):
        print(f"[{i}/{len(runs)}] {run_ref.variant} seed {run_ref.seed} ({run_ref.path})",
              flush=True)  # fmt: skip
        results.append(evaluate_run(run_ref, names, args.episodes, args.seed,
                                    progress=lambda line: print(line, flush=True)))  # fmt: skip
    data = {
        "robot": robot.name, "episodes": args.episodes, "env_seed": args.seed,
        "perturbations": names, "metrics": list(table.metrics), "cycle": table.cycle_name,
        "seconds": time.perf_counter() - start,
        "variants": summarise(results, table.metrics),
        "verdicts": verdicts(results, names), "runs": results,
    }  # fmt: skip
    for path in write_outputs(out, data):
        print(f"wrote {path}")
    print(
        f"{len(runs)} runs x {1 + sum(len(table.axes[n].levels) for n in names)} "
        f"evaluations in {data['seconds']:.0f} s"
    )
    return 0
