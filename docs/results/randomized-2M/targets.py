"""Randomised against nominal training, from a robustness suite's ``robustness.json``.

    python docs/results/randomized-2M/targets.py docs/results/randomized-2M/robustness.json

Prints two tables (Markdown):

1. The issue's target: a randomised-training ``cpg-actor`` keeps at least 80 % of its nominal
   hop height at the middle level of every perturbation. The suite runs 4 levels, so both
   middle ones (the 2nd and the 3rd) are judged. Per seed, the retention is the hop height at
   the level over the same run's nominal hop height; the estimate is the mean over seeds with a
   percentile bootstrap 95 % CI (`cpg_actor.statistics`). Met: the whole CI at or
   above 0.8; missed: the whole CI below; otherwise not resolved.
2. The nominal cost of randomising: nominal return and hop height of ``NAME-randomized``
   minus ``NAME``'s, difference of means with its CI.
"""

from __future__ import annotations

import sys

from cpg_actor.api import statistics as st
from cpg_actor.inputs import read_json, run_script

TARGET = 0.8
MIDDLE = (1, 2)  # indices of the 2nd and 3rd of the suite's 4 levels


def judge(values: list[float]) -> tuple[st.Interval | None, str]:
    """The mean retention over seeds, its CI, and the verdict against the 80 % target."""
    interval = st.bootstrap(values, "mean")
    if interval is None or not st.enough_seeds(values):
        return interval, "not tested"
    return interval, verdict(interval)


def verdict(interval: st.Interval) -> str:
    if interval.low >= TARGET:
        return "met"
    if interval.high < TARGET:
        return "missed"
    return "not resolved"


def hop_retention(runs: list[dict], name: str, index: int) -> list[float]:
    """Per run: hop height at level ``index`` of perturbation ``name`` over its nominal one."""
    return [
        run["perturbations"][name]["levels"][index]["hop_height"] / run["nominal"]["hop_height"]
        for run in runs
    ]


def main(path: str) -> None:
    data = read_json(path, "the robustness.json cpg-actor robustness writes")
    by_variant: dict[str, list[dict]] = {}
    for run in data["runs"]:
        by_variant.setdefault(run["variant"], []).append(run)
    randomized = [v for v in by_variant if v.endswith("-randomized")]

    print("| variant | perturbation | level | hop height kept [95 % CI] | >= 80 % |")
    print("| --- | --- | ---: | --- | --- |")
    for variant in randomized + [v[: -len("-randomized")] for v in randomized]:
        runs = by_variant.get(variant, [])
        for name in data["perturbations"]:
            for index in MIDDLE:
                level = runs[0]["perturbations"][name]["levels"][index]["level"]
                interval, result = judge(hop_retention(runs, name, index))
                print(f"| `{variant}` | {name} | {level:g} | {interval} | {result} |")

    print("\n| variant | nominal return | nominal hop height (m) | vs nominal training: "
          "return | hop height (m) |")  # fmt: skip
    print("| --- | ---: | ---: | --- | --- |")
    for variant in randomized:
        base = variant[: -len("-randomized")]
        row = []
        for key in ("return", "hop_height"):
            mine = [run["nominal"][key] for run in by_variant[variant]]
            theirs = [run["nominal"][key] for run in by_variant.get(base, [])]
            row.append((sum(mine) / len(mine), st.bootstrap_difference(mine, theirs)))
        print(f"| `{variant}` | {row[0][0]:.0f} | {row[1][0]:.3f} | {row[0][1]} | {row[1][1]} |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(f"usage: python {sys.argv[0]} ROBUSTNESS.json")
    sys.exit(run_script(lambda: main(sys.argv[1]), "randomized-2M/targets.py"))
