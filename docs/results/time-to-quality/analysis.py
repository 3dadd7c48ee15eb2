"""The analysis that `PROTOCOL.md` fixes, from the JSON files of the two runs of
`benchmarks/time_to_quality.py` (``time_to_quality.json``, ``search_budgets.json`` in FOLDER, or
their ``.gz``):
the time to the target of the CPG-Actor against every other method (12 tests), and the
search-budget sweep (9 tests), each family Holm-corrected.

    PYTHONPATH=src python docs/results/time-to-quality/analysis.py docs/results/time-to-quality \\
        > docs/results/time-to-quality/analysis.md
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from cpg_actor.api import statistics as st
from cpg_actor.inputs import read_json as read_file
from cpg_actor.inputs import run_script
from cpg_actor_studies import family as f

CPG = "`cpg-actor`"
SWEPT = ("`cpg-actor`", "`mlp-warm`", "`cho2019-warm`")
LAST = 5  # evaluations averaged for the final return and apex
RATIO_EFFECT = 1.25
RELATIVE_EFFECT = 0.05


def time_to_target(run: dict[str, Any], key: str) -> float:
    """The wall time or env steps of the first evaluation at the target, or, when none was,
    of the last evaluation (an underestimate of its time)."""
    hit = run["hit"] if run["hit"] is not None else run["curve"][-1]
    return float(hit[key])


def final(run: dict[str, Any], key: str) -> float:
    values = [h[key] for h in run["curve"][-LAST:] if h[key] is not None]
    return float(np.nanmean(values)) if values else math.nan


def shown_ci(values: list[float], log: bool) -> str:
    return str(f.mean_ci(values, log))


def time_tests(runs: dict[str, list[dict[str, Any]]]) -> list[dict[str, Any]]:
    """``cpg-actor`` against every other method on log wall time and log env steps to the
    target; > 0 means ``cpg-actor`` is faster."""
    tests = []
    for key in ("wall", "steps"):
        cpg = np.log([time_to_target(r, key) for r in runs[CPG]])
        for label, others in runs.items():
            if label == CPG:
                continue
            other = np.log([time_to_target(r, key) for r in others])
            difference, p = st.welch_test(other, cpg)
            tests.append({"group": f"{key} to the target", "label": f"{CPG} vs {label}",
                          "test": st.WELCH, "difference": difference, "p": p, "log": True,
                          "minimum": math.log(RATIO_EFFECT)})  # fmt: skip
    f.judge(tests)
    return tests


def sweep_tests(runs: dict[str, list[dict[str, Any]]], budgets: list[str]) -> list[dict[str, Any]]:
    tests = []
    for budget in budgets:
        cpg = runs[f"{CPG} (search {budget})"]
        end = [final(r, "return") for r in cpg]
        start = [float(r["curve"][0]["return"]) for r in cpg]
        difference, p = st.paired_t_test(end, start)
        tests.append({"group": f"search {budget}", "label": f"{CPG}: final - start",
                      "test": st.PAIRED, "difference": difference, "p": p, "log": False,
                      "minimum": RELATIVE_EFFECT * abs(float(np.mean(start)))})  # fmt: skip
        for other in SWEPT[1:]:
            values = [final(r, "return") for r in runs[f"{other} (search {budget})"]]
            difference, p = st.welch_test(end, values)
            tests.append({"group": f"search {budget}", "label": f"{CPG} - {other}",
                          "test": st.WELCH, "difference": difference, "p": p, "log": False,
                          "minimum": RELATIVE_EFFECT * abs(float(np.mean(values)))})  # fmt: skip
    f.judge(tests)
    return tests


def read_json(folder: Path, name: str) -> Any:
    """``NAME.json`` as the benchmark writes it, or ``NAME.json.gz`` as it is committed (the
    docs' size budget); None when neither is there."""
    for path in (folder / f"{name}.json", folder / f"{name}.json.gz"):
        if path.is_file():
            return read_file(path, "benchmarks/time_to_quality.py's JSON")
    return None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    args = parser.parse_args()
    quality = read_json(args.folder, "time_to_quality")
    if quality is None:
        sys.exit(f"{args.folder / 'time_to_quality.json'}: no such file, nor its .gz (the "
                 "protocol's first command writes it)")  # fmt: skip
    sweep = read_json(args.folder, "search_budgets")
    budgets = sorted({label.split("(search ")[1].rstrip(")") for label in sweep or {}},
                     key=lambda b: float(b.rstrip("k").replace(",", "")))  # fmt: skip
    if CPG not in quality or (sweep is not None and not budgets):
        sys.exit(f"{args.folder}: the JSON files lack `cpg-actor` or the swept budgets")

    print("# Time to quality and the search-budget sweep: the analysis of `PROTOCOL.md`\n")
    print(f"Made by `PYTHONPATH=src python docs/results/time-to-quality/analysis.py "
          f"{' '.join(sys.argv[1:])}`. Means over seeds with 95 % percentile-bootstrap CIs "
          "(display; times as geometric means). A seed that missed the target counts at its "
          "last evaluation.\n")  # fmt: skip
    print("## Time to the target\n")
    print("| method | seeds at the target | wall time (s) | env steps | final return | "
          "final hop apex (m) |\n| --- | --- | ---: | ---: | ---: | ---: |")  # fmt: skip
    for label, runs in quality.items():
        reached = sum(r["hit"] is not None for r in runs)
        print(f"| {label} | {reached}/{len(runs)} | "
              f"{shown_ci([time_to_target(r, 'wall') for r in runs], True)} | "
              f"{shown_ci([time_to_target(r, 'steps') for r in runs], True)} | "
              f"{shown_ci([final(r, 'return') for r in runs], False)} | "
              f"{shown_ci([final(r, 'apex') for r in runs], False)} |")  # fmt: skip
    times = time_tests(quality)
    print(f"\n{len(times)} tests, {st.family_text(len(times))}; the difference is the factor by "
          "which `cpg-actor` is faster (> 1: faster), the minimum a factor "
          f"{RATIO_EFFECT}.\n")  # fmt: skip
    print("\n".join(f.table(times)))
    print("\n## The search-budget sweep\n")
    if sweep is None:  # a family of its own: the first one stands without it
        print("Not yet run: no `search_budgets.json` (the protocol's second command).")
        return
    print("| method | start return | final return | final hop apex (m) | seeds at the target |")
    print("| --- | ---: | ---: | ---: | --- |")
    for label, runs in sweep.items():
        print(f"| {label} | {shown_ci([r['curve'][0]['return'] for r in runs], False)} | "
              f"{shown_ci([final(r, 'return') for r in runs], False)} | "
              f"{shown_ci([final(r, 'apex') for r in runs], False)} | "
              f"{sum(r['hit'] is not None for r in runs)}/{len(runs)} |")  # fmt: skip
    tests = sweep_tests(sweep, budgets)
    print(f"\n{len(tests)} tests, {st.family_text(len(tests))}; minimum effect 5 % of the start "
          "or of the other agent's mean.\n")  # fmt: skip
    print("\n".join(f.table(tests)))


if __name__ == "__main__":
    sys.exit(run_script(main, "time-to-quality/analysis.py"))  # a bad input: one line
