"""The figure of this folder's README (display only): each run's terrain level over training
(its curriculum), and per command of the evaluation protocol's grid at the middle level, each
agent's linear-velocity error and share of episodes that fell (the mean over seeds as a bar,
each seed as a dot), with the issue's rough-ground targets for the grid's means.

    PYTHONPATH=src python docs/results/go1-rough/figure.py docs/results/go1-rough \\
        docs/results/go1-rough/rough_ground.png

Reads what ``analysis.py`` reads (``FOLDER/grid/ROLE/seedS/grid.json`` and the runs' terrain
levels, from ``FOLDER/runs`` or ``FOLDER/terrain_levels.json``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from analysis import (  # this folder's analysis: its names, targets and reader
    ERROR_TARGET,
    FALL_TARGET,
    GRID_FILE,
    LEVEL,
    ROLES,
    ROUGH,
    START,
    read_curricula,
)

from cpg_actor.api import save_figure
from cpg_actor.inputs import read_json, run_script
from cpg_actor.robustness import protocol

ORDER = (ROLES[0], START, *ROLES[1:])  # the CPG-Actor beside its start
LABELS = {START: "the CPG-Actor's start"}
PANELS = {  # grid key: (label, the target for the grid's mean)
    "lin_vel_error": ("linear-velocity error (m/s)", ERROR_TARGET),
    "fell": ("share of episodes that fell", FALL_TARGET),
}
FORMATS = (".png", ".svg", ".pdf")


def level_rows(folder: Path) -> dict[str, list[dict[str, dict]]]:
    """Per role, per seed, its grid rows at the middle level by command."""
    found = {}
    for role in ORDER:
        seeds = sorted((folder / "grid" / role).glob("seed*/grid.json"))
        found[role] = [
            {row["command"]: row for row in read_json(p, GRID_FILE, nulls_as_nan=True)["rows"]
             if row["terrain"] == ROUGH and not row["check"]}
            for p in seeds
        ]  # fmt: skip
    found = {role: seeds for role, seeds in found.items() if seeds and all(seeds)}
    if not found:
        sys.exit(f"{folder / 'grid'}: no ROLE/seedS/grid.json with {ROUGH!r} rows "
                 f"(`cpg-actor eval RUN --grid --grid-levels {LEVEL}`)")  # fmt: skip
    return found


def draw(curricula: dict[str, dict[int, list]], rows: dict, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(12, 8))
    grid = fig.add_gridspec(2, 2, width_ratios=(1, 2.2))
    curve = fig.add_subplot(grid[:, 0])
    bars = [fig.add_subplot(grid[0, 1])]
    bars.append(fig.add_subplot(grid[1, 1], sharex=bars[0]))
    colours = {role: f"C{i}" for i, role in enumerate(ORDER)}
    for role, variant in zip(ROLES, curricula, strict=True):
        for i, levels in enumerate(curricula[variant].values()):
            steps = np.array([s for s, _ in levels], dtype=float) / 1e6
            curve.plot(steps, [v for _, v in levels], color=colours[role], lw=1, alpha=0.8,
                       label=LABELS.get(role, role) if i == 0 else None)  # fmt: skip
    curve.set_xlabel("env steps (millions)")
    curve.set_ylabel("terrain level of the episodes that ended (0-9)")
    curve.set_title("The curriculum, a line per run", fontsize=10)
    curve.legend(fontsize=8)
    curve.grid(alpha=0.3)
    commands = [c.name for c in protocol.GRID]
    x = np.arange(len(commands))
    width = 0.8 / len(rows)
    for axis, (key, (label, target)) in zip(bars, PANELS.items(), strict=True):
        for i, (role, seeds) in enumerate(rows.items()):
            values = np.array([[s[c][key] if c in s else np.nan for c in commands]
                               for s in seeds])  # fmt: skip
            offset = x - 0.4 + width * (i + 0.5)
            axis.bar(offset, np.nanmean(values, axis=0), width, alpha=0.75,
                     color=colours[role], label=LABELS.get(role, role))  # fmt: skip
            for seed in values:
                axis.plot(offset, seed, "o", ms=2.5, color=colours[role], mec="black", mew=0.3)
        axis.axhline(target, color="tab:red", ls="--", lw=1,
                     label=f"target for the grid's mean ({target:g})")  # fmt: skip
        axis.set_ylabel(label)
        axis.grid(axis="y", alpha=0.3)
    bars[0].set_title(f"The command grid at level {LEVEL} (every kind of tile)", fontsize=10)
    bars[0].legend(fontsize=8, ncol=2)
    bars[1].set_xticks(x, commands, rotation=30, ha="right")
    bars[0].tick_params(labelbottom=False)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path, help="the folder analysis.py reads")
    parser.add_argument("output", type=Path, help="the figure (.png, .svg or .pdf)")
    parser.add_argument("--variants", default=",".join(ROLES),
                        help="the reproduction's two variants, CPG-Actor first")  # fmt: skip
    args = parser.parse_args()
    if args.output.suffix.lower() not in FORMATS:
        parser.error(f"output {args.output}: a figure file is needed, one of {', '.join(FORMATS)}")
    variants = tuple(v.strip() for v in args.variants.split(","))
    if len(variants) != 2 or not all(variants):
        parser.error(f"--variants takes two names, CPG-Actor first, got {args.variants!r}")
    rows = level_rows(args.folder)
    print(draw(read_curricula(args.folder, variants, keep=False), rows, args.output))


if __name__ == "__main__":
    sys.exit(run_script(main, "go1-rough/figure.py"))  # a missing or damaged input: one line
