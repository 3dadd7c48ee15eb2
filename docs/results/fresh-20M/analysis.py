"""The analysis that `PROTOCOL.md` fixes, from the report of a finished `cpg-actor reproduce`
folder (its ``summary.json``): per metric the variant with the best mean against the 2 others
(10 tests) and the paper's "about 6x Cho et al.'s reward at 20M steps" (1 test), one family,
Holm-corrected; next to each variant its 2M values from ``../fresh-2M`` (other seeds: shown,
not tested).

    cpg-actor reproduce ...   # the protocol's; it writes results/fresh-20M/summary.json
    PYTHONPATH=src python docs/results/fresh-20M/analysis.py results/fresh-20M/summary.json \\
        --figure docs/results/fresh-20M/comparison.png > docs/results/fresh-20M/analysis.md

Also writes ``analysis.json`` (every per-seed value and test) beside the summary.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from cpg_actor.api import atomic_write_text
from cpg_actor.api import statistics as st
from cpg_actor.inputs import InputError, read_json, run_script
from cpg_actor_studies import family as f

HERE = Path(__file__).resolve().parent
AT_2M = HERE.parent / "fresh-2M" / "summary.json"
VARIANTS = ("cpg-actor", "mlp-warm", "cho2019-warm")
# name: (summary key, higher is better, tested on the logarithm)
METRICS: dict[str, tuple[str, bool, bool]] = {
    "return": ("final_return", True, False),
    "hop apex (m)": ("hop_apex", True, False),
    "joint smoothness (rad^2)": ("joint_smoothness", False, True),
    "command smoothness (rad^2)": ("smoothness", False, True),
    "torque rate (N m/s)": ("torque_rate", False, True),
}
RATIO_EFFECT = 1.25  # smoothness and torque rate: a factor
RELATIVE_EFFECT = 0.05  # return and hop apex: of the other variant's mean
CLAIMED_RATIO = (3.0, 12.0)  # "about 6x": the ratio of mean returns inside this band


def per_seed(summary: dict[str, Any], variant: str, key: str) -> list[float]:
    values = summary["variants"].get(variant, {}).get("per_seed", {}).get(key, [])
    return [float(v) if v is not None else math.nan for v in values]


def minimum(log: bool):
    """The smallest difference that counts, on the scale the test uses."""
    if log:
        return lambda other: math.log(RATIO_EFFECT)
    return lambda other: RELATIVE_EFFECT * abs(float(np.nanmean(other)))


def analyse(summary: dict[str, Any]) -> dict[str, Any]:
    """Every per-seed value, the family's tests (judged) and the pick per metric."""
    missing = [v for v in VARIANTS if len(per_seed(summary, v, "final_return")) < 2]
    if missing:
        raise ValueError(f"the summary lacks 2 or more seeds of {missing}; it holds "
                         f"{sorted(summary['variants'])}")  # fmt: skip
    unfinished = {
        v: summary["variants"][v].get("finished")
        for v in VARIANTS
        if summary["variants"][v].get("finished") != summary["variants"][v]["seeds"]
    }
    if unfinished:  # runs carried across sittings: judge only the finished comparison
        raise ValueError(f"runs not finished yet (finished per variant: {unfinished} of "
                         f"{summary['variants'][VARIANTS[0]]['seeds']} seeds)")  # fmt: skip
    data = {name: {v: per_seed(summary, v, key) for v in VARIANTS}
            for name, (key, _, _) in METRICS.items()}  # fmt: skip
    tests: list[dict[str, Any]] = []
    best: dict[str, str] = {}
    for name, (_, higher, log) in METRICS.items():
        best[name], group = f.best_against_others(data[name], name, higher, log, minimum(log))
        tests += group
    cpg, cho = data["return"]["cpg-actor"], data["return"]["cho2019-warm"]
    difference, p = st.welch_test(cpg, cho)
    ratio = float(np.nanmean(cpg) / np.nanmean(cho))
    tests.append({"group": "the paper's claim", "label": "cpg-actor - cho2019-warm, return",
                  "test": st.WELCH, "difference": difference, "log": False, "p": p,
                  "minimum": RELATIVE_EFFECT * abs(float(np.nanmean(cho)))})  # fmt: skip
    f.judge(tests)
    low, high = CLAIMED_RATIO
    claim = {"ratio": ratio, "band": list(CLAIMED_RATIO),
             "supported": bool(tests[-1]["passed"] and low <= ratio <= high)}  # fmt: skip
    return {"data": data, "tests": tests, "best": best, "claim": claim}


def verdict(name: str, best: str, tests: list[dict[str, Any]]) -> str:
    group = [t for t in tests if t["group"] == name]
    tied = [t["label"].split(" vs ")[1] for t in group if not t["passed"]]
    beaten = [t["label"].split(" vs ")[1] for t in group if t["passed"]]
    if not tied:
        return f"**Pick `{best}`**: it beats both others."
    text = f"`{best}` has the best mean; not separated from " + ", ".join(f"`{v}`" for v in tied)
    return text + ("; it beats " + ", ".join(f"`{v}`" for v in beaten) if beaten else "") + "."


def report(result: dict[str, Any], summary: dict[str, Any], at_2m: dict[str, Any] | None) -> None:
    data, tests, best = result["data"], result["tests"], result["best"]
    print("# fresh-20M: the analysis of `PROTOCOL.md`\n")
    print(
        "Made by `PYTHONPATH=src python docs/results/fresh-20M/analysis.py "
        + " ".join(sys.argv[1:])
        + "`. Seeds per variant: "
        + ", ".join(f"`{v}` {summary['variants'][v]['seeds']}" for v in VARIANTS)
        + ".\n"
    )
    print(
        f"One family of {len(tests)} tests, {st.family_text(len(tests))}; a difference counts "
        f"when its Holm p < 0.05 and it is at least its minimum effect (return and hop apex "
        f"{RELATIVE_EFFECT:.0%} of the other side's mean, smoothness and torque rate a factor "
        f"{RATIO_EFFECT}, tested on the logarithm, so ranked and shown by their geometric "
        "mean). Means with 95 % percentile-bootstrap CIs over seeds (display only); the 2M "
        "column is `fresh-2M` (seeds 10-14, shown, not tested).\n"
    )
    for name, (key, higher, log) in METRICS.items():
        print(f"## {name} ({'higher' if higher else 'lower'} is better)\n")
        kind = "geometric mean" if log else "mean"
        print(f"| variant | {kind} at 20M [95 % CI] | per seed | at 2M (fresh-2M) |")
        print("| --- | ---: | --- | ---: |")
        for v in VARIANTS:
            seeds = ", ".join(st.three_figures(x) for x in data[name][v])
            earlier = f.mean_ci(per_seed(at_2m, v, key), log) if at_2m else None
            print(f"| `{v}`{' (best)' if v == best[name] else ''} | "
                  f"{f.mean_ci(data[name][v], log)} | {seeds} | {earlier or '-'} |")  # fmt: skip
        print("\n" + verdict(name, best[name], tests) + "\n")
    claim, test = result["claim"], tests[-1]
    print("## The paper's claim: about 6x Cho et al.'s reward at 20M steps\n")
    print(
        f"Ratio of mean returns `cpg-actor` / `cho2019-warm`: {claim['ratio']:.2f} (supported "
        f"only inside [{claim['band'][0]:g}, {claim['band'][1]:g}] with `cpg-actor` ahead, "
        f"Holm p < 0.05 and at least the minimum); difference {test['difference']:+.1f}, "
        f"Holm p {test['adjusted']:.2g}: **{'supported' if claim['supported'] else 'not supported'}"
        "**.\n"
    )
    print("## Every test\n")
    print(
        "The last column: yes, the difference counts; reversed, the other side is ahead by "
        "at least the minimum with Holm p < 0.05; no, neither.\n"
    )
    print("\n".join(f.table(tests)))


def figure(data: dict[str, dict[str, list[float]]], path: Path) -> None:
    """Per metric one panel: each seed's value per variant (dots) and the mean (line;
    geometric on log axes, where the test takes logarithms)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from cpg_actor.api import save_figure

    fig, axes = plt.subplots(1, len(METRICS), figsize=(15, 3.6), constrained_layout=True)
    for ax, (name, (_, higher, log)) in zip(axes, METRICS.items(), strict=True):
        columns = [(v, data[name][v], "C0" if v == "cpg-actor" else "0.3") for v in VARIANTS]
        f.seed_panel(ax, columns, log, f"{name}\n({'higher' if higher else 'lower'} is better)")
    fig.suptitle("The hopper's warm-started agents at 20M steps, fresh seeds 15-19 (line: "
                 "mean, geometric on log axes; dots: seeds)", fontsize=10)  # fmt: skip
    save_figure(fig, path)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("summary", type=Path, help="the report's summary.json")
    parser.add_argument("--figure", type=Path, help="also draw the per-seed values (PNG)")
    args = parser.parse_args()
    if not args.summary.is_file():
        sys.exit(f"{args.summary}: no such file; give the summary.json that "
                 "`cpg-actor reproduce` (or `cpg-actor figures`) writes")  # fmt: skip
    summary = read_json(args.summary, "the summary.json cpg-actor reproduce writes")
    try:
        result = analyse(summary)
    except InputError:
        raise  # it names the file itself
    except ValueError as error:
        sys.exit(f"{args.summary}: {error}")
    at_2m = read_json(AT_2M) if AT_2M.is_file() else None
    report(result, summary, at_2m)
    if args.figure:
        figure(result["data"], args.figure)
    atomic_write_text(json.dumps(result, indent=1) + "\n", args.summary.parent / "analysis.json")


if __name__ == "__main__":
    sys.exit(run_script(main, "fresh-20M/analysis.py"))  # a missing or damaged input: one line
