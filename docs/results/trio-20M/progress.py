"""Peak and final evaluation return of every run of a reproduction, finished or not: the
"no collapse" check (final >= 0.95 x peak), with the report's own definitions
(``cpg_actor_studies.reproduction.numbers``: the mean of the last evaluations, the best moving
mean).

    python docs/results/trio-20M/progress.py results/trio-20M
    python docs/results/trio-20M/progress.py --curves curves.png RUN [RUN ...]   # eval curves
    python docs/results/trio-20M/progress.py --at 2M results/trio-20M   # also the return at 2M

It reads the runs' ``metrics.jsonl``: a results directory of your own (the trio's runs are in
git history; its README says how to restore them into ``results/trio-20M``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from cpg_actor.api import parse_steps
from cpg_actor.inputs import InputError, read_jsonl, run_script
from cpg_actor_studies.reproduction.numbers import final_return, peak_return


def evaluations(run: Path) -> tuple[list[float], list[float]]:
    rows = read_jsonl(run / "metrics.jsonl", "a run's metrics, as cpg-actor train logs them")
    rows = [r for r in rows if r.get("eval/return") is not None]
    if not rows:
        raise InputError(f"{run / 'metrics.jsonl'}: no evaluation logged yet (eval/return)")
    return [r["global_step"] for r in rows], [r["eval/return"] for r in rows]


def label(run: Path) -> str:
    return f"{run.parent.name}/{run.name}" if run.name.startswith("seed") else run.name


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("paths", nargs="+", type=Path)
    parser.add_argument("--curves", type=Path, help="a figure of the runs' eval returns")
    parser.add_argument(
        "--at", type=parse_steps, help="also the return at this step (the same mean, e.g. 2M)"
    )
    args = parser.parse_args()
    runs = []
    for path in args.paths:
        runs += sorted(path.glob("runs/*/seed*")) if (path / "runs").is_dir() else [path]
    at = f" return at {args.at / 1e6:g}M |" if args.at else ""
    print(f"| run | steps | peak (at) | final | final / peak |{at}")
    print("| --- | ---: | --- | ---: | ---: |" + (" ---: |" if args.at else ""))
    for run in runs:
        steps, returns = evaluations(run)
        peak, at = peak_return(steps, returns)
        final = final_return(steps, returns)
        row = f"| {label(run)} | {steps[-1] / 1e6:.1f}M | {peak:.0f} ({at / 1e6:.1f}M) | "
        row += f"{final:.0f} | {final / peak:.3f} |"
        if args.at:
            row += f" {final_return(steps, returns, at_step=args.at):.0f} |"
        print(row)
    if args.curves:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 4))
        for run in runs:
            steps, returns = evaluations(run)
            ax.plot([s / 1e6 for s in steps], returns, label=label(run), lw=1)
        ax.set(xlabel="env steps (M)", ylabel="deterministic eval return")
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(args.curves, dpi=110)


if __name__ == "__main__":
    sys.exit(run_script(main, "trio-20M/progress.py"))  # a missing or damaged input: one line
