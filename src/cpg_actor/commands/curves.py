"""`cpg-actor curves`: the learning curves of several training runs in one figure.

Each run directory's ``metrics.jsonl`` gives one line per ``--metric`` against the training
steps (a thin line per run); runs are grouped by their agent (from their ``config.yaml``; or
each on its own, ``--group-by run``),
and each group's mean over its runs is drawn thick where all of them logged the metric at the
same steps. The last logged value of every metric, per run and per group (mean and standard
deviation), is printed and written as a JSON file next to the figure.

    cpg-actor curves runs/mlp_s0 runs/mlp_s1 runs/cpg_s0 runs/cpg_s1 \\
        --metric eval/speed_error --metric eval/return --max-steps 5M --out curves.png
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

HELP = "draw the learning curves of several runs (grouped by agent) in one figure"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("runs", nargs="+", help="run directories written by `cpg-actor train`")
    parser.add_argument(
        "--metric",
        action="append",
        default=None,
        help="a key of metrics.jsonl, repeatable (default: eval/return)",
    )
    parser.add_argument("--out", default="curves.png", help="the figure (.png); JSON beside it")
    parser.add_argument(
        "--max-steps",
        default=None,
        help="only rows up to this many training steps (runs of different lengths compared at "
        "one budget)",
    )
    parser.add_argument(
        "--group-by",
        choices=["agent", "run"],
        default="agent",
        help="agent: one colour and a mean per agent (default); run: one per run directory",
    )
    parser.add_argument("--title", default=None, help="the figure's title")
    parser.add_argument("--overwrite", action="store_true", help="replace existing files")


def load_run(run: Path) -> tuple[str, list[dict]]:
    """The agent of a run directory and the rows of its ``metrics.jsonl``."""
    from cpg_actor.config import TrainConfig

    config, metrics = run / "config.yaml", run / "metrics.jsonl"
    for path in (config, metrics):
        if not path.is_file():
            raise FileNotFoundError(f"{path} does not exist; is {run} a training run directory?")
    rows = [json.loads(line) for line in metrics.read_text().splitlines() if line.strip()]
    return TrainConfig.load(config).agent, rows


def series(rows: list[dict], metric: str) -> tuple[list[int], list[float]]:
    """(steps, values) of the rows that logged ``metric`` with a finite value."""
    pairs = [(int(r["global_step"]), float(r[metric])) for r in rows
             if isinstance(r.get(metric), int | float) and math.isfinite(r[metric])]  # fmt: skip
    return [s for s, _ in pairs], [v for _, v in pairs]


def run(args: argparse.Namespace) -> int:
    import numpy as np
    from matplotlib.figure import Figure

    from cpg_actor.checkpoint import atomic_write_text
    from cpg_actor.config import parse_steps
    from cpg_actor.plots import save_figure

    metrics = args.metric or ["eval/return"]
    out = Path(args.out)
    if out.suffix != ".png":
        raise ValueError(f"--out must end in .png, got {out}")
    summary_path = out.with_suffix(".json")
    for path in (out, summary_path):
        if path.exists() and not args.overwrite:
            raise FileExistsError(f"{path} exists; pass --overwrite to replace it")
    runs = {str(Path(r)): load_run(Path(r)) for r in args.runs}
    if args.max_steps is not None:
        limit = parse_steps(args.max_steps)
        runs = {name: (agent, [r for r in rows if r["global_step"] <= limit])
                for name, (agent, rows) in runs.items()}  # fmt: skip
    for metric in metrics:
        if not any(series(rows, metric)[0] for _, rows in runs.values()):
            raise ValueError(f"no run logged {metric!r} (a key of metrics.jsonl, e.g. "
                             "eval/return, charts/episode_return)")  # fmt: skip
    groups: dict[str, list[str]] = {}
    for name, (agent, _) in runs.items():
        groups.setdefault(agent if args.group_by == "agent" else Path(name).name, []).append(name)

    fig = Figure(figsize=(5.0 * len(metrics), 3.8), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, len(metrics)))
    summary: dict = {"runs": {}, "agents": {}}
    for axis, metric in zip(axes, metrics, strict=True):
        for colour, (agent, names) in enumerate(groups.items()):
            curves = [series(runs[name][1], metric) for name in names]
            for steps, values in curves:
                axis.plot(steps, values, color=f"C{colour}", alpha=0.3, lw=0.8)
            common = [c for c in curves if c[0]]
            if common and all(c[0] == common[0][0] for c in common):
                mean = np.mean([c[1] for c in common], axis=0)
                label = f"{agent} (mean of {len(common)})"
                axis.plot(common[0][0], mean, color=f"C{colour}", lw=2, label=label)
            else:
                axis.plot([], [], color=f"C{colour}", lw=2, label=f"{agent} ({len(names)} runs)")
            finals = [c[1][-1] for c in curves if c[1]]
            for name, (steps, values) in zip(names, curves, strict=True):
                if values:
                    summary["runs"].setdefault(name, {"agent": agent})[metric] = {
                        "step": steps[-1], "value": values[-1]}  # fmt: skip
            if finals:
                summary["agents"].setdefault(agent, {})[metric] = {
                    "mean": float(np.mean(finals)), "std": float(np.std(finals)),
                    "runs": len(finals)}  # fmt: skip
        axis.set_xlabel("training steps")
        axis.set_ylabel(metric)
        axis.grid(alpha=0.3)
        axis.legend(fontsize=8)
    fig.suptitle(args.title or f"{len(runs)} runs")
    save_figure(fig, out)
    atomic_write_text(json.dumps(summary, indent=2) + "\n", summary_path)
    for agent, values in summary["agents"].items():
        text = ", ".join(f"{m} {v['mean']:.4g} +- {v['std']:.2g} ({v['runs']} runs)"
                         for m, v in values.items())  # fmt: skip
        print(f"{agent}: last logged {text}")
    print(f"figure {out}; summary {summary_path}")
    return 0
