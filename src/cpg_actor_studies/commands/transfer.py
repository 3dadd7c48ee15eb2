"""`cpg-actor transfer`: every final policy of a reproduction evaluated in both simulators."""

from __future__ import annotations

import argparse
from pathlib import Path

HELP = "evaluate a reproduction's final policies in both simulators (cross-simulator transfer)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("out", help="results directory written by `cpg-actor reproduce`")
    parser.add_argument("--episodes", type=int, default=5, help="episodes per policy and sim")
    parser.add_argument("--seed", type=int, default=1000, help="environment seed (default 1000)")
    what = parser.add_mutually_exclusive_group()
    what.add_argument("--overwrite", action="store_true", help="replace OUT/transfer.json")
    what.add_argument(
        "--add",
        action="store_true",
        help="keep the runs OUT/transfer.json holds and evaluate only the others (runs "
        "finished in later sittings)",
    )


def run(args: argparse.Namespace) -> int:
    from cpg_actor.api import MAX_EPISODES, check_count, check_seed
    from cpg_actor_studies.hopper_paper.report import write_report
    from cpg_actor_studies.transfer import TRANSFER_FILE, write_transfer

    check_seed(args.seed)
    out = Path(args.out)
    if not (out / "runs").is_dir():
        raise FileNotFoundError(f"{out} is not a reproduce results directory (no runs/)")
    check_count(args.episodes, "--episodes", MAX_EPISODES)
    if (out / TRANSFER_FILE).exists() and not (args.overwrite or args.add):
        raise FileExistsError(
            f"{out / TRANSFER_FILE} exists; pass --overwrite to replace it or --add to "
            "evaluate only the runs it lacks"
        )
    path = write_transfer(out, args.episodes, args.seed, add=args.add)
    report = write_report(out)
    print(f"transfer results {path}; report {report}")
    return 0
