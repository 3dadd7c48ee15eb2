"""`cpg-actor reproduce`: the paper's comparison, variants x seeds in parallel, figures, report."""

from __future__ import annotations

import argparse
import os
import shlex
import sys
from pathlib import Path

from cpg_actor.api import PRESETS, add_set_option, all_simulators

HELP = "reproduce the paper: train variants x seeds in parallel (or on Ray), figures and a report"

DEFAULT_VARIANTS = "cpg-actor,cpg-actor-open-loop,cho2019-warm,cho2019,mlp"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--total-steps", default="20M", help="control steps per run, e.g. 50k or 20M (default 20M)"
    )
    parser.add_argument("--seeds", type=int, default=5, help="seeds 0..N-1 per variant (default 5)")
    parser.add_argument(
        "--first-seed", type=int, default=0, help="seeds FIRST..FIRST+N-1 instead (default 0)"
    )
    parser.add_argument(
        "--variants",
        default=DEFAULT_VARIANTS,
        help=f"comma-separated agent names (default {DEFAULT_VARIANTS})",
    )
    parser.add_argument("--out", required=True, help="results directory, e.g. results/NAME")
    parser.add_argument(
        "--workers",
        type=int,
        default=None,
        help=f"parallel runs on this machine (default: the core count, {os.cpu_count()})",
    )
    parser.add_argument("--num-envs", type=int, default=None, help="parallel envs per run")
    parser.add_argument("--sim", default=None, choices=all_simulators())
    parser.add_argument(
        "--preset",
        default=None,
        choices=sorted(PRESETS),
        help="every run's `cpg-actor train --preset` (default paper; gpu: 4,096 MJX envs); a "
        "variant with a recipe of its own keeps it (mlp-playground: playground, "
        "mlp-legged-gym: legged_gym)",
    )
    add_set_option(
        parser, "training config override for every run (repeatable), as in `cpg-actor train`"
    )
    parser.add_argument(
        "--count-search-steps",
        action="store_true",
        help="charge the runs that start from a searched gait (cpg-actor, cho2019-warm, "
        "mlp-warm) with the search's env steps: they train --total-steps minus them",
    )
    parser.add_argument(
        "--eval-episodes", type=int, default=5, help="episodes per stage evaluation (default 5)"
    )
    parser.add_argument(
        "--gpus-per-run",
        type=float,
        default=0.0,
        help="with --ray: the share of a GPU each run asks Ray for (e.g. 0.2: five runs per "
        "GPU; use with --sim mjx --set device=cuda, docs/gpu.md). Default 0",
    )
    parser.add_argument(
        "--ray",
        default=None,
        metavar="ADDRESS",
        help="run on the Ray cluster at ADDRESS ('HOST:6379' as `ray start --head` prints it, "
        "'auto', 'ray://host:10001'; 'local' starts a local instance); a cluster with token "
        "authentication needs RAY_AUTH_MODE=token and its token (docs/reproduction.md, Ray). "
        "Needs pip install cpg-actor[ray]",
    )
    parser.add_argument(
        "--ray-results",
        default="auto",
        choices=("auto", "shared", "return"),
        help="with --ray: how each run reaches OUT. shared: the node writes into OUT (a file "
        "system every node sees at the same path); return: the run trains in a temporary "
        "directory on its node and comes back to this machine as the task's result; auto "
        "(default): shared on the nodes that see OUT, return on the others",
    )
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="replace an OUT made with other settings (deletes it)",
    )
    parser.add_argument(
        "--progress-interval",
        type=float,
        default=30.0,
        help="seconds between progress blocks when not on a terminal (default 30)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no live table")


def run(args: argparse.Namespace) -> int:
    from cpg_actor.api import parse_steps
    from cpg_actor.limits import MAX_WORKERS, check_int
    from cpg_actor_studies.reproduction import execute, plan

    settings = plan.ReproduceSettings(
        variants=plan.parse_variants(args.variants),
        seeds=args.seeds,
        total_steps=parse_steps(args.total_steps),
        num_envs=args.num_envs,
        sim=args.sim,
        preset=getattr(args, "preset", None),
        overrides=list(args.overrides),
        eval_episodes=args.eval_episodes,
        first_seed=args.first_seed,
        count_search_steps=getattr(args, "count_search_steps", False),
    )
    workers = args.workers if args.workers is not None else min(os.cpu_count() or 1, MAX_WORKERS)
    check_int(workers, "--workers", 1, MAX_WORKERS)
    if args.ray is not None:
        execute.import_ray()  # a clear error before anything is written
    if getattr(args, "ray_results", "auto") != "auto" and args.ray is None:
        raise ValueError("--ray-results is for --ray; local runs write into OUT")
    if args.gpus_per_run and args.ray is None:
        raise ValueError(
            "--gpus-per-run is for --ray; on one machine, runs share its GPU as processes: "
            "--workers N with --set device=cuda"
        )
    if not args.gpus_per_run >= 0:
        raise ValueError(f"--gpus-per-run must be >= 0, got {args.gpus_per_run}")
    out = Path(args.out)
    tasks = plan.build_tasks(settings, out, workers)  # validates before anything is written
    if args.ray is None:
        return _run(args, settings, workers, out, tasks)
    execute.connect_ray(args.ray)  # an unreachable cluster or a wrong token: nothing written
    try:
        return _run(args, settings, workers, out, tasks)
    finally:
        execute.disconnect_ray()


def _run(args: argparse.Namespace, settings, workers: int, out: Path, tasks: list) -> int:
    """Everything after validation: write OUT, run the tasks, figures and report."""
    from cpg_actor_studies.hopper_paper.floor import ensure_floor
    from cpg_actor_studies.hopper_paper.report import write_report
    from cpg_actor_studies.reproduction import execute, plan

    ray_results = getattr(args, "ray_results", "auto")
    state = plan.prepare_out_dir(out, settings, args.overwrite)
    command = (
        ["cpg-actor", *sys.argv[1:]]
        if sys.argv[1:2] == ["reproduce"]
        else ["cpg-actor", "reproduce", *_as_argv(args)]
    )
    plan.write_settings_file(
        out,
        settings,
        shlex.join(command),
        {
            "workers": workers,
            "ray": args.ray,
            "gpus_per_run": args.gpus_per_run,
            **({"ray_results": ray_results} if args.ray is not None else {}),
            "runs": len(tasks),
        },
    )
    finished = sum(execute.run_is_finished(task) for task in tasks)
    print(
        f"reproduce: {len(settings.variants)} variant(s) x {settings.seeds} seed(s) = "
        f"{len(tasks)} runs of {settings.total_steps:,} steps in {out} ({state}; {finished} "
        f"already finished); "
        + (f"Ray at {args.ray}" if args.ray else f"{workers} local worker(s)"),
        flush=True,
    )
    for line in plan.stage_warnings(tasks):
        print(f"reproduce: warning: {line}", flush=True)
    live = not args.no_progress and sys.stdout.isatty()
    progress = execute.Progress(tasks, args.progress_interval, live=live)
    try:
        if args.ray is not None:
            results = execute.run_ray(
                tasks,
                args.ray,
                progress,
                args.gpus_per_run,
                results=ray_results,
                out=out,
            )
        else:
            results = execute.run_local(tasks, workers, progress)
    except KeyboardInterrupt:
        print(
            "cpg-actor reproduce: interrupted; re-run the same command to resume",
            file=sys.stderr,
        )
        return 130
    for result in results:
        line = f"  {result['name']}: {result['status']} ({result['action']})"
        if result.get("resources", {}).get("GPU"):
            line += f" on {result['resources']['GPU']:g} GPU"
        if result.get("node"):
            node = result["node"]
            line += f" on node {node['hostname']} ({node['ip']}, {node['id'][:8]})"
        if result.get("error"):
            line += f": {result['error']}"
        print(line)
    from cpg_actor.api import get_robot
    from cpg_actor_studies.reproduction.plan import resolve_config

    robot = get_robot(resolve_config(settings, settings.variants[0]).robot)
    if robot.paper is None:  # the report and its floor are the paper's study of its robot
        print(f"reproduce: runs of {robot.name} in {out / 'runs'}; the report and its claims are "
              "the paper's hopper's (evaluate these runs with `cpg-actor eval RUN`, or `--grid` "
              "on a quadruped)")  # fmt: skip
    else:
        print("reproduce: the open-loop grid floor (960 constant CPG parameter sets)", flush=True)
        ensure_floor(out, settings)
        report = write_report(out, results)
        print(f"report {report}; figures in {out / 'figures'}")
    failed = [r for r in results if r["status"] == "failed"]
    if failed:
        print(
            f"cpg-actor reproduce: {len(failed)} run(s) failed; re-run the same command to retry",
            file=sys.stderr,
        )
        return 1
    return 0


def _as_argv(args: argparse.Namespace) -> list[str]:
    """The command line of ``args`` (when ``run`` is called without ``sys.argv``)."""
    argv = ["--total-steps", str(args.total_steps), "--seeds", str(args.seeds)]
    if getattr(args, "first_seed", 0):
        argv += ["--first-seed", str(args.first_seed)]
    argv += ["--variants", args.variants, "--out", str(args.out)]
    if args.num_envs is not None:
        argv += ["--num-envs", str(args.num_envs)]
    if args.sim is not None:
        argv += ["--sim", args.sim]
    if getattr(args, "preset", None) is not None:
        argv += ["--preset", args.preset]
    if getattr(args, "gpus_per_run", 0):
        argv += ["--gpus-per-run", str(args.gpus_per_run)]
    if getattr(args, "count_search_steps", False):
        argv.append("--count-search-steps")
    for text in args.overrides:
        argv += ["--set", text]
    return argv
