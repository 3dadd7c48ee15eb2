"""A one-at-a-time sensitivity study on reproduce's plan machinery.

Each *setting* is the defaults (``default``) or the defaults with one group of config values
changed (``--vary KEY=V1,V2`` or ``--vary KEY1,KEY2=A1:A2,B1:B2``). A setting is a reproduction
(:class:`~cpg_actor_studies.reproduction.plan.ReproduceSettings`, variants x seeds) in
``OUT/LABEL``, evaluated once at the end; all runs of all settings share one pool of workers.
The summary (``OUT/sensitivity.md``, ``OUT/sensitivity.json``, ``OUT/sensitivity.png``) is
made from the deterministic evaluations logged during training (``eval/return`` and ``eval/``
the robot's headline metric, ``Robot.headline_metric``: the hopper's ``hop_height``; or the episode
metrics ``--metrics`` names, e.g. ``lin_vel_error,fell`` on the quadrupeds' omnidirectional
task). ``OUT`` carries the project's marker (``cpg_actor.files``): a folder without it is
never written in, and ``--overwrite`` deletes there only what the sweep wrote.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from cpg_actor.api import all_metrics, atomic_write_text, read_config, run_robot
from cpg_actor.files import (
    MARKER,
    SWEEP,
    clear_project_dir,
    marker_kind,
    refuse_linked_folders,
    write_marker,
)
from cpg_actor.limits import brief
from cpg_actor_studies.reproduction import plan

FINAL_EVALS = 3  # the score of a run: the mean of its last FINAL_EVALS evaluations


@dataclass(frozen=True)
class Setting:
    label: str  # directory name and table row, e.g. "default", "init_std=0.3"
    overrides: tuple[str, ...]  # --set texts


def parse_vary(text: str) -> list[Setting]:
    """``"agent_config.init_std=0.3,3"`` -> two settings; ``"a,b=1:2,3:4"`` changes a and b
    together (a=1 b=2, then a=3 b=4)."""
    if "=" not in text:
        raise ValueError(f"--vary expects KEY=V1,V2 or KEY1,KEY2=A1:A2,B1:B2, got {brief(text)}")
    keys_text, values_text = text.split("=", 1)
    keys = [k.strip() for k in keys_text.split(",") if k.strip()]
    groups = [g.strip() for g in values_text.split(",") if g.strip()]
    if not keys or not groups:
        raise ValueError(f"--vary {brief(text)} names no key or no value")
    settings = []
    for group in groups:
        values = group.split(":") if len(keys) > 1 else [group]
        if len(values) != len(keys):
            raise ValueError(
                f"--vary {brief(text)}: value group {brief(group)} has {len(values)} values for "
                f"{len(keys)} keys (separate them with ':')"
            )
        short = [k.rsplit(".", 1)[-1] for k in keys]
        label = ",".join(f"{k}={v}" for k, v in zip(short, values, strict=True))
        overrides = tuple(f"{k}={v}" for k, v in zip(keys, values, strict=True))
        settings.append(Setting(label, overrides))
    return settings


def build_settings(varies: list[str]) -> list[Setting]:
    settings = [Setting("default", ())]
    for text in varies:
        settings += parse_vary(text)
    labels = [s.label for s in settings]
    if len(set(labels)) != len(labels):
        raise ValueError(f"two settings have the same label: {labels}")
    return settings


def prepare_out_dir(out: Path, overwrite: bool = False, summary_only: bool = False) -> None:
    """Check ``OUT`` before anything is written there: an existing, non-empty one must be a
    sweep's (carry its marker), else it is refused whole; ``overwrite`` clears it first, only
    if it holds nothing but what the sweep wrote (:func:`cpg_actor.files.clear_project_dir`).
    A new one is made and marked; ``summary_only`` needs a sweep's."""
    if out.exists() and not out.is_dir():
        raise NotADirectoryError(f"--out {out} is a file, not a directory")
    refuse_linked_folders(out)  # its settings' folders: plan.prepare_out_dir
    if not (out.is_dir() and any(out.iterdir())):
        if summary_only:
            raise FileNotFoundError(f"{out} does not exist or is empty; nothing to summarise")
        out.mkdir(parents=True, exist_ok=True)
        write_marker(out, SWEEP)
    elif overwrite:
        clear_project_dir(out, SWEEP, keep=(MARKER,))
    elif marker_kind(out) != SWEEP:
        raise FileExistsError(
            f"--out {out} is not empty and was not made by `cpg-actor sweep` (no {MARKER}; "
            "a sweep made before cpg-actor marked its directories has none either); nothing "
            "in it is replaced: choose another --out"
        )


def reproduce_settings(
    setting: Setting,
    variants: list[str],
    seeds: int,
    total_steps: int,
    overrides: list[str],
    first_seed: int = 0,
    preset: str | None = None,
) -> plan.ReproduceSettings:
    return plan.ReproduceSettings(
        variants=variants,
        seeds=seeds,
        total_steps=total_steps,
        overrides=[*overrides, *setting.overrides],
        stage_fractions=[1.0],
        first_seed=first_seed,
        preset=preset,
    )


def read_evaluations(
    run_dir: Path, metric: str = "hop_height"
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(steps, eval return, eval metric, train wall seconds)`` from ``metrics.jsonl``."""
    rows = []
    path = run_dir / "metrics.jsonl"
    if path.is_file():
        for line in path.read_text().splitlines():
            if line.strip():
                row = json.loads(line)
                if row.get("eval/return") is not None:
                    rows.append(row)
    return (
        np.array([r["global_step"] for r in rows], dtype=float),
        np.array([r["eval/return"] for r in rows], dtype=float),
        np.array([r.get(f"eval/{metric}", math.nan) for r in rows], dtype=float),
        np.array([r.get("time/train_wall") or math.nan for r in rows], dtype=float),
    )


def check_metrics(metrics: list[str], robot: Any) -> list[str]:
    """``metrics`` (episode metrics of ``robot``'s envs) or, when empty, its headline metric;
    ValueError naming the accepted ones otherwise."""
    unknown = [name for name in metrics if name not in robot.metrics]
    if unknown:
        raise ValueError(f"--metrics: {', '.join(unknown)} not an episode metric of robot "
                         f"{brief(robot.name)}; it has {', '.join(robot.metrics)}")  # fmt: skip
    return list(dict.fromkeys(metrics)) or [robot.headline_metric]


def summarize(
    out: Path,
    settings: list[Setting],
    variants: list[str],
    seeds: int,
    first_seed: int = 0,
    metrics: list[str] | None = None,
) -> dict[str, Any]:
    """Per setting and variant: each seed's score (mean of the last evaluations: the return
    and each of ``metrics``, by default the robot's headline metric) and curve. ``metric``
    names the first of them (the score the table is read by)."""
    runs = out / settings[0].label / "runs" / variants[0] / f"seed{first_seed}"
    names = check_metrics(metrics or [], run_robot(read_config(runs)))
    summary: dict[str, Any] = {"final_evals": FINAL_EVALS, "metric": names[0], "metrics": names,
                               "settings": {}}  # fmt: skip
    for setting in settings:
        entry: dict[str, Any] = {"overrides": list(setting.overrides), "variants": {}}
        for variant in variants:
            values: dict[str, list[float]] = {"return": [], **{name: [] for name in names}}
            curves = []
            for seed in range(first_seed, first_seed + seeds):
                run_dir = out / setting.label / "runs" / variant / f"seed{seed}"
                for name in names:
                    steps, ret, score, _ = read_evaluations(run_dir, name)
                    values[name].append(
                        float(score[-FINAL_EVALS:].mean()) if score.size else math.nan
                    )
                values["return"].append(float(ret[-FINAL_EVALS:].mean()) if ret.size else math.nan)
                curves.append({"steps": steps.tolist(), "return": ret.tolist()})
            entry["variants"][variant] = {**values, "curves": curves}
        summary["settings"][setting.label] = entry
    return summary


def _mean_std(values: list[float], digits: int) -> str:
    """Mean ± std over the seeds with a value; one seed's value alone, marked n=1 (its spread
    is unknown, not 0)."""
    a = np.array(values, dtype=float)
    a = a[np.isfinite(a)]
    if a.size == 1:
        return f"{a[0]:.{digits}f} (n=1)"
    return f"{a.mean():.{digits}f} ± {a.std():.{digits}f}" if a.size else "-"


def write_summary(out: Path, summary: dict[str, Any], command: str, seeds: int) -> list[Path]:
    """``sensitivity.json``, ``sensitivity.md`` (table) and ``sensitivity.png`` (curves)."""
    atomic_write_text(json.dumps(summary, indent=1) + "\n", out / "sensitivity.json")
    labels = list(summary["settings"])
    variants = list(next(iter(summary["settings"].values()))["variants"])
    names = summary.get("metrics") or [summary.get("metric", "hop_height")]
    columns = [all_metrics()[n].column if n in all_metrics() else n for n in names]
    lines = [
        "# Sensitivity of PPO settings (one at a time around the defaults)",
        "",
        f"Produced by `{command}`.",
        "",
        f"Score of a run: the mean of its last {summary['final_evals']} deterministic "
        "evaluations (`eval/return`, "
        + ", ".join(f"`eval/{n}`" for n in names)
        + f", 5 episodes each); mean ± std over "
        f"{seeds} seeds (one seed: its value alone, n=1, no interval); *steps*: the fewest "
        "env steps any seed's run reached (less than the budget for runs that did not "
        "finish). The first row is the defaults; every other row changes only the values it "
        "names.",
        "",
        "| setting | "
        + " | ".join(
            " | ".join([f"{v} return", *(f"{v} {c}" for c in columns), f"{v} steps"])
            for v in variants
        )
        + " |",
        "| --- | " + " | ".join(" | ".join(["---:"] * (len(names) + 2)) for _ in variants) + " |",
    ]
    for label in labels:
        cells = []
        for variant in variants:
            data = summary["settings"][label]["variants"][variant]
            reached = [c["steps"][-1] if c["steps"] else 0 for c in data["curves"]]
            cells += [
                _mean_std(data["return"], 0),
                *(_mean_std(data[n], 3) for n in names),
                f"{min(reached) / 1000:.0f}k",
            ]
        lines.append(f"| `{label}` | " + " | ".join(cells) + " |")
    atomic_write_text("\n".join(lines) + "\n", out / "sensitivity.md")
    figure = out / "sensitivity.png"
    _plot(summary, figure)
    return [out / "sensitivity.md", out / "sensitivity.json", figure]


def _plot(summary: dict[str, Any], path: Path) -> None:
    from matplotlib.figure import Figure

    from cpg_actor.api import save_figure

    labels = list(summary["settings"])
    variants = list(next(iter(summary["settings"].values()))["variants"])
    fig = Figure(figsize=(6 * len(variants), 4))
    axes = fig.subplots(1, len(variants), squeeze=False)
    for ax, variant in zip(axes[0], variants, strict=True):
        for i, label in enumerate(labels):
            curves = summary["settings"][label]["variants"][variant]["curves"]
            curves = [c for c in curves if c["steps"]]
            if not curves:
                continue
            length = min(len(c["steps"]) for c in curves)
            steps = np.array(curves[0]["steps"][:length])
            values = np.array([c["return"][:length] for c in curves])
            style = "-" if i < 10 else "--"
            width = 2.5 if label == "default" else 1.2
            ax.plot(steps, values.mean(0), style, lw=width, label=label)
        ax.set_title(variant)
        ax.set_xlabel("control steps")
        ax.set_ylabel("deterministic eval return (mean over seeds)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
