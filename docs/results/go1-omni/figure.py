"""The figure of this folder's README (display only): per command of the evaluation
protocol's grid, each variant's linear-velocity and yaw-rate error on flat ground, the mean over
seeds as a bar and each seed as a dot, with the issue's targets for the grid's means.

    PYTHONPATH=src python docs/results/go1-omni/figure.py docs/results/go1-omni \\
        docs/results/go1-omni/grid_errors.png

Reads ``FOLDER/grid/VARIANT/seedS/grid.json`` (``cpg-actor eval --grid``; ``start`` the
CPG-Actor's start), as ``analysis.py`` does; also for ``../anymal-omni/``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from analysis import GRID_FILE, START, TARGETS, VARIANTS  # this folder's analysis: names, targets

from cpg_actor.api import save_figure
from cpg_actor.inputs import read_json, run_script
from cpg_actor.robustness import protocol

ORDER = (VARIANTS[0], START, *VARIANTS[1:])  # the CPG-Actor beside its start
LABELS = {START: "the CPG-Actor's start"}
PANELS = {
    "lin_vel_error": "linear-velocity error (m/s)",
    "yaw_rate_error": "yaw-rate error (rad/s)",
}
FORMATS = (".png", ".svg", ".pdf")


def flat_rows(folder: Path) -> dict[str, list[dict[str, dict]]]:
    """Per variant, per seed, its flat-ground grid rows by command."""
    found = {}
    for variant in ORDER:
        seeds = sorted((folder / "grid" / variant).glob("seed*/grid.json"))
        found[variant] = [
            {row["command"]: row for row in read_json(p, GRID_FILE, nulls_as_nan=True)["rows"]
             if row["terrain"] == "flat" and not row["check"]}
            for p in seeds
        ]  # fmt: skip
    found = {v: seeds for v, seeds in found.items() if seeds}
    if not found:
        sys.exit(f"{folder / 'grid'}: no VARIANT/seedS/grid.json (`cpg-actor eval RUN --grid`)")
    return found


def draw(rows: dict[str, list[dict[str, dict]]], path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    commands = [c.name for c in protocol.GRID]
    fig, axes = plt.subplots(len(PANELS), 1, figsize=(11, 6.5), sharex=True)
    width = 0.8 / len(rows)
    x = np.arange(len(commands))
    for axis, (key, label) in zip(axes, PANELS.items(), strict=True):
        target = TARGETS[key]
        for i, (variant, seeds) in enumerate(rows.items()):
            values = np.array([[s[c][key] if c in s else np.nan for c in commands]
                               for s in seeds])  # fmt: skip
            offset = x - 0.4 + width * (i + 0.5)
            bars = axis.bar(offset, np.nanmean(values, axis=0), width,
                            label=f"{LABELS.get(variant, variant)}",
                            alpha=0.75)  # fmt: skip
            colour = bars.patches[0].get_facecolor()
            for seed in values:
                axis.plot(offset, seed, "o", ms=2.5, color=colour, mec="black", mew=0.3)
        axis.axhline(target, color="tab:red", ls="--", lw=1,
                     label=f"target for the grid's mean ({target:g})")  # fmt: skip
        axis.set_ylabel(label)
        axis.grid(axis="y", alpha=0.3)
    axes[-1].set_xticks(x, commands, rotation=30, ha="right")
    fig.suptitle("The command grid on flat ground: the mean over seeds (bars), each seed (dots)")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="upper center", ncol=5, fontsize=8,
               bbox_to_anchor=(0.5, 0.95))  # fmt: skip
    fig.tight_layout(rect=(0, 0, 1, 0.93))
    save_figure(fig, path)
    plt.close(fig)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path, help="holds grid/VARIANT/seedS/grid.json")
    parser.add_argument("output", type=Path, help="the figure (.png, .svg or .pdf)")
    args = parser.parse_args()
    if args.output.suffix.lower() not in FORMATS:
        parser.error(f"output {args.output}: a figure file is needed, one of {', '.join(FORMATS)}")
    print(draw(flat_rows(args.folder), args.output))


if __name__ == "__main__":
    sys.exit(run_script(main, "go1-omni/figure.py"))  # a missing or damaged input: one line
