"""`cpg-actor sweep`: a one-at-a-time sensitivity study of config values, variants x seeds."""

from __future__ import annotations

import argparse
import dataclasses
import os
import shlex
import sys
from pathlib import Path

from cpg_actor.api import PRESETS, add_set_option

HELP = "sensitivity study: train variants x seeds for the defaults and each --vary setting"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", required=True, help="results directory")
    parser.add_argument(
        "--variants", default="mlp,cpg-actor", help="agents (default mlp,cpg-actor)"
    )
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..N-1 (default 3)")
    parser.add_argument(
        "--first-seed",
        type=int,
        default=0,
        help="seeds FIRST..FIRST+N-1 instead (tuning on seeds that are never reported)",
    )
    parser.add_argument("--total-steps", default="300k", help="steps per run (default 300k)")
    parser.add_argument(
        "--vary",
        action="append",
        default=[],
        metavar="KEY=V1,V2",
        help="one setting per value, the rest at the defaults (repeatable); several keys "
        "changed together: KEY1,KEY2=A1:A2,B1:B2",
    )
    parser.add_argument(
        "--preset",
        default=None,
        choices=sorted(PRESETS),
        help="every run's `cpg-actor train --preset` (default: the robot's recipe; omni: the "
        "quadrupeds' omnidirectional task, with --set robot=go1 or anymal)",
    )
    add_set_option(parser, "a config value for every run (repeatable)")
    parser.add_argument(
        "--metrics",
        default="",
        metavar="NAME[,NAME]",
        help="episode metrics scored besides the return, the first the one the table is read "
        "by (default: the robot's headline metric, the hopper's hop_height; e.g. "
        "lin_vel_error,fell on the quadrupeds' omnidirectional task)",
    )
    parser.add_argument(
        "--workers", type=int, default=None, help=f"parallel runs (default {os.cpu_count()})"
    )
    parser.add_argument(
        "--summary-only",
        action="store_true",
        help="train nothing: write the summary from the runs in OUT as they are (unfinished "
        "runs are scored at the step they reached, which the table shows)",
    )
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="start OUT over: delete what an earlier sweep wrote there (only in a directory "
        "`cpg-actor sweep` made, holding nothing else)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no live table")
    parser.add_argument(
        "--progress-interval", type=float, default=30.0, help="seconds between progress blocks"
    )


def run(args: argparse.Namespace) -> int:
    from cpg_actor.api import get_robot, parse_steps
    from cpg_actor.files import refuse_linked_folders
    from cpg_actor.limits import MAX_WORKERS, check_int
    from cpg_actor_studies import sweep
    from cpg_actor_studies.reproduction import plan

    variants = plan.parse_variants(args.variants)
    settings = sweep.build_settings(args.vary)
    total_steps = parse_steps(args.total_steps)
    workers = args.workers if args.workers is not None else min(os.cpu_count() or 1, MAX_WORKERS)
    check_int(workers, "--workers", 1, MAX_WORKERS)
    out = Path(args.out)
    plans = []
    for setting in settings:  # validate every setting before anything is written
        reproduction = sweep.reproduce_settings(
            setting,
            variants,
            args.seeds,
            total_steps,
            args.overrides,
            args.first_seed,
            args.preset,
        )
        plans.append(
            (setting, reproduction, plan.build_tasks(reproduction, out / setting.label, workers))
        )
    command = (
        shlex.join(["cpg-actor", *sys.argv[1:]])
        if sys.argv[1:2] == ["sweep"]
        else "cpg-actor sweep"
    )
    metrics = [name.strip() for name in args.metrics.split(",") if name.strip()]
    sweep.check_metrics(metrics, get_robot(plan.resolve_config(plans[0][1], variants[0]).robot))
    if args.summary_only and args.overwrite:
        raise ValueError("--summary-only and --overwrite exclude each other")
    refuse_linked_folders(out)  # and every setting's folders, before anything is written
    for setting, _, _ in plans:
        plan.refuse_linked_out(out / setting.label)
    sweep.prepare_out_dir(out, args.overwrite, args.summary_only)  # before anything is written
    tasks = []
    if args.summary_only:
        plans = []
    for setting, reproduction, setting_tasks in plans:
        plan.prepare_out_dir(out / setting.label, reproduction, overwrite=False)
        plan.write_settings_file(
            out / setting.label, reproduction, command, {"workers": workers, "sweep": str(out)}
        )
        tasks += [dataclasses.replace(task, group=setting.label) for task in setting_tasks]
    print(
        f"sweep: {len(settings)} settings x {len(variants)} variant(s) x {args.seeds} seed(s) = "
        f"{len(tasks)} runs of {total_steps:,} steps in {out}, {workers} worker(s)",
        flush=True,
    )
    results = []
    if tasks:
        results = _train(tasks, workers, args)
        if results is None:
            return 130
    failed = [r for r in results if r["status"] == "failed"]
    summary = sweep.summarize(out, settings, variants, args.seeds, args.first_seed, metrics)
    for path in sweep.write_summary(out, summary, command, args.seeds):
        print(f"wrote {path}")
    if failed:
        for result in failed:
            print(f"  {result['name']}: failed: {result.get('error')}", file=sys.stderr)
        return 1
    return 0


def _train(tasks, workers: int, args: argparse.Namespace):
    from cpg_actor_studies.reproduction import execute

    progress = execute.Progress(
        tasks, args.progress_interval, live=not args.no_progress and sys.stdout.isatty()
    )
    try:
        return execute.run_local(tasks, workers, progress)
    except KeyboardInterrupt:
        print("cpg-actor sweep: interrupted; re-run the same command to resume", file=sys.stderr)
        return None
