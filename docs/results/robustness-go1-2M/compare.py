"""The Go1's trained CPG-Actor against its own untrained start, from the suite's JSON.

    python docs/results/robustness-go1-2M/compare.py docs/results/robustness-go1-2M/robustness.json

Prints (Markdown) per perturbation and level the mean over seeds of the speed error (m/s) and
the share of episodes that fell, for ``cpg-actor`` and ``untrained``, then the verdict
"cpg-actor more robust than untrained" per perturbation, judged as the suite judges its
claims (`cpg_actor.robustness.verdicts.verdict_more_robust`: the return retained, averaged
over the levels, per seed; Welch's t-test, Holm-corrected over the perturbations, and the
minimum effect of retention).
"""

from __future__ import annotations

import sys

import numpy as np

from cpg_actor.inputs import read_json, run_script
from cpg_actor.robustness.summary import retention_scores
from cpg_actor.robustness.verdicts import verdict_more_robust
from cpg_actor.statistics import decide

VARIANTS = ("cpg-actor", "untrained")


def mean_over_seeds(runs: list[dict], variant: str, name: str | None, index: int, key: str):
    """The mean over ``variant``'s runs of ``key`` at level ``index`` of perturbation ``name``
    (None: the nominal evaluation)."""
    values = [
        (run["nominal"] if name is None else run["perturbations"][name]["levels"][index])[key]
        for run in runs
        if run["variant"] == variant
    ]
    return float(np.mean(values))


def main(path: str) -> None:
    data = read_json(path, "the robustness.json cpg-actor robustness writes")
    runs = data["runs"]
    header = " | ".join(f"`{v}`: speed error, fell" for v in VARIANTS)
    print(f"| perturbation | level | {header} |")
    print("| --- | --- | " + " | ".join("---" for _ in VARIANTS) + " |")
    cells = [f"{mean_over_seeds(runs, v, None, 0, 'speed_error'):.3f}, "
             f"{mean_over_seeds(runs, v, None, 0, 'fell'):.0%}" for v in VARIANTS]  # fmt: skip
    print(f"| nominal | | {' | '.join(cells)} |")
    for name in data["perturbations"]:
        levels = runs[0]["perturbations"][name]["levels"]
        unit = runs[0]["perturbations"][name]["unit"]
        for index, level in enumerate(levels):
            cells = [f"{mean_over_seeds(runs, v, name, index, 'speed_error'):.3f}, "
                     f"{mean_over_seeds(runs, v, name, index, 'fell'):.0%}"
                     for v in VARIANTS]  # fmt: skip
            print(f"| {name} | {level['level']:g} {unit} | {' | '.join(cells)} |")
    print("\n| perturbation | verdict | why |\n| --- | --- | --- |")
    claims = [
        verdict_more_robust(retention_scores(runs, VARIANTS[0], name),
                            retention_scores(runs, VARIANTS[1], name), VARIANTS)
        for name in data["perturbations"]
    ]  # fmt: skip
    for name, (verdict, why) in zip(data["perturbations"], decide(claims), strict=True):
        print(f"| {name} | {verdict} | {why} |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(f"usage: python {sys.argv[0]} ROBUSTNESS.json")
    sys.exit(run_script(lambda: main(sys.argv[1]), "robustness-go1-2M/compare.py"))
