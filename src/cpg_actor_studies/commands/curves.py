"""`cpg-actor curves`: the learning curves of several training runs in one figure.

Each run directory's ``metrics.jsonl`` gives one line per ``--metric`` against the training
steps. Runs are grouped by what they trained (``--group-by config``, the default): the agent,
the robot, the step budget and every other config value except the seed and the run's
mechanics (:data:`NOT_TRAINING`: devices, threads, logging, checkpoints, compilation). Runs of
different budgets or settings are never averaged together; a group's legend names the values
that set it apart from the other groups of its agent. A group of one run is one line ("1
run"); a group of several is a thin line per run and their mean, thick, at the steps where
every run of the group logged the metric, with a 95% confidence band of the mean (Student t
over the runs). ``--group-by run``: each run on its own.

The figure goes to ``--out`` (default ``curves.png`` in the first run's directory, never the
working directory); the last logged value of every metric, per run and per group (mean and
standard deviation), is printed and written as a JSON file next to it. Existing files are kept
unless ``--overwrite``.

    cpg-actor curves runs/mlp_s0 runs/mlp_s1 runs/cpg_s0 runs/cpg_s1 \\
        --metric eval/speed_error --metric eval/return --max-steps 5M --out figures/curves.png
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

from cpg_actor.limits import brief

HELP = "draw the learning curves of several runs (grouped by agent and settings) in one figure"

# config keys that do not change what a run trains: runs differing only here are one group
NOT_TRAINING = frozenset({
    "seed", "preset", "device", "torch_threads", "update_threads", "env_threads",
    "checkpoint_interval", "eval_interval", "log_interval", "histogram_interval",
    "ppo.compile", "ppo.fused_step", "ppo.skip_guard_checks",
    "env.render_width", "env.render_height",
})  # fmt: skip
SHOWN_DIFFERENCES = 2  # config differences named in a legend label; more are counted


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("runs", nargs="+", help="run directories written by `cpg-actor train`")
    parser.add_argument(
        "--metric",
        action="append",
        default=None,
        help="a key of metrics.jsonl, repeatable (default: eval/return)",
    )
    parser.add_argument(
        "--out",
        default=None,
        help="the figure (.png), its JSON summary beside it (default: curves.png in the first "
        "run's directory)",
    )
    parser.add_argument(
        "--max-steps",
        default=None,
        help="only rows up to this many training steps (runs of different lengths compared at "
        "one budget; runs of different budgets stay in groups of their own)",
    )
    parser.add_argument(
        "--group-by",
        choices=["config", "agent", "run"],
        default="config",
        help="config: one colour and a mean per agent, robot, budget and settings (default; "
        "'agent' is the same); run: one per run directory",
    )
    parser.add_argument("--title", default=None, help="the figure's title")
    parser.add_argument("--overwrite", action="store_true", help="replace existing files")


def load_run(run: Path) -> tuple[dict[str, Any], list[dict]]:
    """The config (as a nested mapping) of a run directory and the rows of its
    ``metrics.jsonl``."""
    from cpg_actor.api import TrainConfig
    from cpg_actor.inputs import read_jsonl

    config, metrics = run / "config.yaml", run / "metrics.jsonl"
    for path in (config, metrics):
        if not path.is_file():
            raise FileNotFoundError(f"{path} does not exist; is {run} a training run directory?")
    rows = read_jsonl(metrics, "the metrics cpg-actor train logs")
    return TrainConfig.load(config).to_dict(), rows


def series(rows: list[dict], metric: str) -> tuple[list[int], list[float]]:
    """(steps, values) of the rows that logged ``metric`` with a finite value."""
    pairs = [(int(r["global_step"]), float(r[metric])) for r in rows
             if isinstance(r.get(metric), int | float) and math.isfinite(r[metric])]  # fmt: skip
    return [s for s, _ in pairs], [v for _, v in pairs]


def flatten(config: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """A nested config mapping as ``{dotted key: value}`` (lists as tuples, hashable)."""
    out: dict[str, Any] = {}
    for key, value in config.items():
        if isinstance(value, dict):
            out.update(flatten(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = tuple(value) if isinstance(value, list) else value
    return out


def training_key(config: dict[str, Any]) -> tuple:
    """What a run trained: its config without :data:`NOT_TRAINING` (a hashable group key)."""
    flat = flatten(config)
    return tuple(sorted((k, repr(v)) for k, v in flat.items() if k not in NOT_TRAINING))


def value_text(key: str, value: Any) -> str:
    from cpg_actor.api import steps_text

    if key == "total_steps":
        return f"{steps_text(int(value))} steps"
    return f"{key}={value}"


def group_labels(configs: dict[tuple, dict[str, Any]]) -> dict[tuple, str]:
    """A legend label per group (key -> a run's flat config): the agent, the robot when the
    groups' robots differ, then, among the groups of the same agent and robot, the budget if
    theirs differ and each other value in which the group departs from the most common one."""
    from collections import Counter

    robots = {config["robot"] for config in configs.values()}
    base = {key: config["agent"] + (f" on {config['robot']}" if len(robots) > 1 else "")
            for key, config in configs.items()}  # fmt: skip
    labels = {}
    for key, config in configs.items():
        alike = [configs[k] for k in configs if base[k] == base[key]]
        names = sorted({name for other in alike for name in other} - NOT_TRAINING)
        shown = []
        for name in names:
            counts = Counter(repr(other.get(name)) for other in alike).most_common()
            if len(counts) == 1:  # the same in every group
                continue
            tied = counts[0][1] == counts[1][1]
            if name == "total_steps" or tied or repr(config.get(name)) != counts[0][0]:
                shown.append(name)
        shown.sort(key=lambda name: name != "total_steps")  # the budget first
        texts = [value_text(name, config.get(name)) for name in shown[:SHOWN_DIFFERENCES]]
        if len(shown) > SHOWN_DIFFERENCES:
            texts.append(f"+{len(shown) - SHOWN_DIFFERENCES} more settings")
        labels[key] = ", ".join([base[key], *texts])
    texts = list(labels.values())
    return {  # a difference left unnamed: the groups it leaves alike are numbered
        key: f"{label} (group {number})" if texts.count(label) > 1 else label
        for number, (key, label) in enumerate(labels.items(), 1)
    }


def mean_band(curves: list[tuple[list[int], list[float]]]):
    """``(steps, mean, half width of the 95% band)`` at the steps where every curve has a value
    (``None`` if there is none); the band: Student t's 0.975 quantile over the curves."""
    import numpy as np
    from scipy import stats

    common = sorted(set.intersection(*(set(steps) for steps, _ in curves)))
    if not common:
        return None
    table = np.array([[dict(zip(s, v, strict=True))[step] for step in common] for s, v in curves])
    n = len(curves)
    half = stats.t.ppf(0.975, n - 1) * table.std(axis=0, ddof=1) / math.sqrt(n)
    return np.array(common), table.mean(axis=0), half


def run(args: argparse.Namespace) -> int:
    import numpy as np
    from matplotlib.figure import Figure

    from cpg_actor.api import atomic_write_text, parse_steps, save_figure, step_axis

    metrics = args.metric or ["eval/return"]
    out = Path(args.out) if args.out is not None else Path(args.runs[0]) / "curves.png"
    if out.suffix != ".png":
        raise ValueError(f"--out must end in .png, got {out}")
    runs = {str(Path(r)): load_run(Path(r)) for r in args.runs}
    if args.max_steps is not None:
        limit = parse_steps(args.max_steps)
        runs = {name: (config, [r for r in rows if r["global_step"] <= limit])
                for name, (config, rows) in runs.items()}  # fmt: skip
    logged = sorted({key for _, rows in runs.values() for row in rows for key in row
                     if key != "global_step" and series(rows, key)[0]})  # fmt: skip
    for metric in metrics:  # before the files: a typo is not reported as an existing file
        if metric not in logged:
            raise ValueError(f"no run logged {brief(metric)}; the runs logged: "
                             f"{', '.join(logged) or 'nothing'}")  # fmt: skip
    summary_path = out.with_suffix(".json")
    for path in (out, summary_path):
        if path.exists() and not args.overwrite:
            raise FileExistsError(f"{path} exists; pass --overwrite to replace it (or --out)")

    groups: dict[tuple, list[str]] = {}  # group key -> its runs
    configs: dict[tuple, dict[str, Any]] = {}  # group key -> a run's flat config
    for name, (config, _) in runs.items():
        key = (name,) if args.group_by == "run" else training_key(config)
        groups.setdefault(key, []).append(name)
        configs.setdefault(key, flatten(config))
    if args.group_by == "run":
        basenames = [Path(name).name for name in runs]
        labels = {(name,): Path(name).name if basenames.count(Path(name).name) == 1 else name
                  for name in runs}  # fmt: skip
    else:
        labels = group_labels(configs)

    largest = max(max(series(rows, m)[0], default=0) for _, rows in runs.values() for m in metrics)
    scale, xlabel = step_axis(largest)

    fig = Figure(figsize=(5.0 * len(metrics), 3.8), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, len(metrics)))
    summary: dict = {"runs": {}, "groups": {}}
    for key, names in groups.items():
        config = configs[key]
        summary["groups"][labels[key]] = {
            "agent": config["agent"], "robot": config["robot"],
            "total_steps": config["total_steps"], "runs": names, "metrics": {}}  # fmt: skip
    for axis, metric in zip(axes, metrics, strict=True):
        for colour, (key, names) in enumerate(groups.items()):
            label, colour = labels[key], f"C{colour}"
            curves = [series(runs[name][1], metric) for name in names]
            if len(names) == 1:
                steps, values = curves[0]
                axis.plot(np.array(steps) / scale, values, color=colour, lw=1.5,
                          label=f"{label}, 1 run")  # fmt: skip
            else:
                for steps, values in curves:
                    axis.plot(np.array(steps) / scale, values, color=colour, alpha=0.3, lw=0.8)
                band = mean_band(curves)
                if band is None:
                    axis.plot([], [], color=colour, lw=2,
                              label=f"{label}, {len(names)} runs (no steps in common)")  # fmt: skip
                else:
                    steps, mean, half = band
                    x = steps / scale
                    axis.plot(x, mean, color=colour, lw=2,
                              label=f"{label}, mean of {len(names)} runs ± 95% CI")  # fmt: skip
                    axis.fill_between(x, mean - half, mean + half, color=colour, alpha=0.2, lw=0)
            for name, (steps, values) in zip(names, curves, strict=True):
                if values:
                    summary["runs"].setdefault(name, {"group": label})[metric] = {
                        "step": steps[-1], "value": values[-1]}  # fmt: skip
            finals = [values[-1] for _, values in curves if values]
            if finals:
                summary["groups"][label]["metrics"][metric] = {
                    "mean": float(np.mean(finals)), "std": float(np.std(finals)),
                    "runs": len(finals)}  # fmt: skip
        axis.set_xlabel(xlabel)
        axis.set_ylabel(metric)
        axis.grid(alpha=0.3)
        axis.legend(fontsize=8)
    fig.suptitle(args.title or f"{len(runs)} runs")
    save_figure(fig, out)
    atomic_write_text(json.dumps(summary, indent=2) + "\n", summary_path)
    for label, group in summary["groups"].items():
        text = ", ".join(f"{m} {v['mean']:.4g} +- {v['std']:.2g} ({v['runs']} "
                         f"run{'s' if v['runs'] > 1 else ''})"
                         for m, v in group["metrics"].items())  # fmt: skip
        print(f"{label}: last logged {text}" if text else f"{label}: none of the metrics logged")
    print(f"figure {out}; summary {summary_path}")
    return 0
