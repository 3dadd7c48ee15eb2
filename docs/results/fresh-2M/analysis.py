"""The analysis that `PROTOCOL.md` fixes, from a finished `cpg-actor reproduce` folder and its
robustness suite: per metric the variant with the best mean against each other variant, the
CPG-Actor against its start, the open-loop CPG-Actor against Cho et al. (warm); one family of
33 tests, Holm-corrected; with ``--smooth``, the matched-smoothness MLP at each strength
against the CPG-Actor, a family of its own (10 tests).

    PYTHONPATH=src python docs/results/fresh-2M/analysis.py results/fresh-2M \\
        --evaluate-starts --smooth results/fresh-2M-smooth-a0.1 results/fresh-2M-smooth-a0.2 \\
        > docs/results/fresh-2M/analysis.md

``--evaluate-starts`` runs ``cpg-actor eval`` on each ``cpg-actor`` run's checkpoint before
its first update (into ``OUT/starts/seedS/traces.npz``, kept); without it those evaluations
must already be there. Also writes ``OUT/analysis.json`` (every per-seed value and test).
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np

from cpg_actor.api import atomic_write_text
from cpg_actor.api import statistics as st
from cpg_actor.inputs import load_npz, read_json, read_yaml, run_script
from cpg_actor_studies import family as f

VARIANTS = ("cpg-actor", "cpg-actor-open-loop", "open-loop-es", "mlp", "mlp-warm",
            "cho2019-warm")  # fmt: skip
# name: (summary key or None for the suite's, higher is better, log scale, minimum effect text)
METRICS: dict[str, tuple[str | None, bool, bool]] = {
    "return": ("final_return", True, False),
    "hop apex (m)": ("hop_apex", True, False),
    "joint smoothness (rad^2)": ("joint_smoothness", False, True),
    "command smoothness (rad^2)": ("smoothness", False, True),
    "torque rate (N m/s)": ("torque_rate", False, True),
    "latency retention": (None, True, False),
}
RATIO_EFFECT = 1.25  # smoothness and torque rate: a factor
RETENTION_EFFECT = 0.05  # absolute
RELATIVE_EFFECT = 0.05  # return and hop apex: of the other variant's mean


def per_seed(summary: dict[str, Any], variant: str, key: str) -> list[float]:
    values = summary["variants"].get(variant, {}).get("per_seed", {}).get(key, [])
    return [float(v) if v is not None else math.nan for v in values]


def latency_retention(suite: dict[str, Any], variant: str) -> list[float]:
    """Per seed, the mean over the latency levels of the return kept (a share of nominal)."""
    rows = sorted((run for run in suite["runs"] if run["variant"] == variant),
                  key=lambda run: run["seed"])  # fmt: skip
    return [float(np.mean([level["retention"] for level in run["perturbations"]["latency"]
                           ["levels"]])) for run in rows]  # fmt: skip


SUMMARY = "the summary.json cpg-actor reproduce writes"


def minimum(name: str, other: list[float]) -> float:
    """The smallest difference that counts, on the scale the test uses."""
    if METRICS[name][2]:
        return math.log(RATIO_EFFECT)
    if name == "latency retention":
        return RETENTION_EFFECT
    return RELATIVE_EFFECT * abs(float(np.nanmean(other)))


def start_values(out: Path, evaluate: bool) -> dict[str, list[float]]:
    """Per ``cpg-actor`` seed: return and hop apex at its start and at its end, both from
    ``cpg-actor eval`` (5 episodes, env seed 1000)."""
    values: dict[str, list[float]] = {"start_return": [], "start_apex": [], "end_return": [],
                                      "end_apex": [], "seeds": []}  # fmt: skip
    for run in sorted((out / "runs" / "cpg-actor").glob("seed*")):
        traces = out / "starts" / run.name / "traces.npz"
        if not traces.is_file():
            if not evaluate:
                sys.exit(f"{traces} is missing: run with --evaluate-starts")
            traces.parent.mkdir(parents=True, exist_ok=True)
            subprocess.run([sys.executable, "-m", "cpg_actor.cli", "eval", str(run),
                            "--checkpoint", str(run / "checkpoints" / "iter_000000.pt"),
                            "--episodes", "5", "--output", str(traces)],
                           check=True, stdout=subprocess.DEVNULL)  # fmt: skip
        stages = read_json(run / "eval" / "stages.json", "cpg-actor reproduce's stages", list)
        end = run / stages[-1]["traces"]
        for side, path in (("start", traces), ("end", end)):
            data = load_npz(path, "cpg-actor eval's traces")
            values[f"{side}_return"].append(float(np.mean(data["episode_return"])))
            values[f"{side}_apex"].append(float(np.mean(data["physical_hop_apex"])))
        values["seeds"].append(int(run.name.removeprefix("seed")))
    return values


def matched_smoothness(cpg: dict[str, Any], folders: list[Path]) -> list[dict[str, Any]]:
    """Each filtered ``mlp-warm`` folder against ``cpg-actor`` on the metrics the protocol
    names: Welch, two-sided, the difference oriented so that > 0 favours the filtered MLP."""
    tests: list[dict[str, Any]] = []
    for strength, folder in enumerate(folders, start=1):
        summary = read_json(folder / "summary.json", SUMMARY)
        overrides = read_yaml(folder / "reproduce.yaml", "cpg-actor reproduce's")["settings"]
        alpha = next((o.replace("env.command_filter=", "alpha ") for o in
                      overrides["overrides"] or [] if o.startswith("env.command_filter=")),
                     folder.name)  # fmt: skip
        for name, (key, higher, log) in METRICS.items():
            if key is None:
                continue
            scale = np.log if log else np.asarray
            mlp, actor = per_seed(summary, "mlp-warm", key), per_seed(cpg, "cpg-actor", key)
            a, b = scale(mlp), scale(actor)
            difference, p = st.welch_test(a if higher else b, b if higher else a)
            tests.append(
                {
                    "group": name,
                    "label": f"strength {strength} ({alpha})",
                    "test": st.WELCH,
                    "difference": difference,
                    "log": log,
                    "p": p,
                    "minimum": minimum(name, actor),
                    "mlp": mlp,
                    "cpg": actor,
                }
            )
    return f.judge(tests)


def print_matched(tests: list[dict[str, Any]]) -> None:
    print("\n## The matched-smoothness MLP against the CPG-Actor\n")
    print(
        f"`mlp-warm` behind a low-pass on its command, each strength against `cpg-actor`; "
        f"a family of its own of {len(tests)} tests, {st.family_text(len(tests))}, the same "
        "minimum effects. *Difference*: the filtered MLP's side minus the CPG-Actor's, "
        "oriented so that > 0 favours the MLP (for smoothness and torque rate the factor "
        "by which the MLP's is lower). *Verdict*: MLP ahead, CPG-Actor ahead, or not "
        "separated.\n"
    )
    print(
        "| metric | strength | filtered `mlp-warm` [95 % CI] | `cpg-actor` [95 % CI] | "
        "difference | minimum | p | Holm p | verdict |"
    )
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |")
    for t in tests:
        sides = [str(f.mean_ci(values, t["log"])) for values in (t["mlp"], t["cpg"])]
        verdict = ("MLP ahead" if t["passed"] else "CPG-Actor ahead" if t["reversed"]
                   else "not separated")  # fmt: skip
        print(
            f"| {t['group']} | {t['label']} | {sides[0]} | {sides[1]} | "
            f"{f.shown(t['difference'], t['log'])} | {f.shown(t['minimum'], t['log'])} | "
            f"{t['p']:.2g} | {t['adjusted']:.2g} | {verdict} |"
        )


def figure(
    data: dict[str, dict[str, list[float]]], matched: list[dict[str, Any]], path: Path
) -> None:
    """Per metric one panel: each seed's value per variant (dots), the variant's mean (line;
    geometric on log axes, where the test takes logarithms); the filtered MLPs at the right."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from cpg_actor.api import save_figure

    fig, axes = plt.subplots(2, 3, figsize=(13, 7), constrained_layout=True)
    for ax, (name, (_, higher, log)) in zip(axes.flat, METRICS.items(), strict=True):
        columns = [(v, data[name][v]) for v in VARIANTS]
        columns += [(f"mlp-warm {t['label'].split('(')[1].rstrip(')')}", t["mlp"])
                    for t in matched if t["group"] == name]  # fmt: skip
        coloured = [(label, values, "C0" if label == "cpg-actor" else
                     "C1" if i >= len(VARIANTS) else "0.3")
                    for i, (label, values) in enumerate(columns)]  # fmt: skip
        f.seed_panel(ax, coloured, log, f"{name} ({'higher' if higher else 'lower'} is better)")
    fig.suptitle("The hopper's agents at 2M steps, fresh seeds 10-14 (line: mean, geometric "
                 "on log axes; dots: seeds)", fontsize=10)  # fmt: skip
    save_figure(fig, path)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="the reproduce folder (results/fresh-2M)")
    parser.add_argument("--evaluate-starts", action="store_true")
    parser.add_argument(
        "--smooth",
        type=Path,
        nargs="*",
        default=[],
        help="the matched-smoothness folders, strength 1 first",
    )
    parser.add_argument("--figure", type=Path, help="also draw the per-seed values (PNG)")
    args = parser.parse_args()
    summary = read_json(args.out / "summary.json", SUMMARY)
    suite = read_json(args.out / "robustness" / "robustness.json",
                      "the robustness.json cpg-actor robustness writes")  # fmt: skip

    data = {name: {v: (per_seed(summary, v, key) if key else latency_retention(suite, v))
                   for v in VARIANTS} for name, (key, _, _) in METRICS.items()}  # fmt: skip
    tests: list[dict[str, Any]] = []
    best: dict[str, str] = {}
    for name, (_, higher, log) in METRICS.items():
        best[name], group = f.best_against_others(
            data[name], name, higher, log, lambda other, name=name: minimum(name, other)
        )
        tests += group
    starts = start_values(args.out, args.evaluate_starts)
    for what, end, start in (("return", "end_return", "start_return"),
                             ("hop apex (m)", "end_apex", "start_apex")):  # fmt: skip
        difference, p = st.paired_t_test(starts[end], starts[start])
        tests.append(
            {
                "group": "cpg-actor beyond its start",
                "label": f"{what}: end - start",
                "test": st.PAIRED,
                "difference": difference,
                "log": False,
                "p": p,
                "minimum": RELATIVE_EFFECT * abs(float(np.mean(starts[start]))),
            }
        )
    open_loop, cho = data["return"]["cpg-actor-open-loop"], data["return"]["cho2019-warm"]
    difference, p = st.welch_test(open_loop, cho)
    tests.append({"group": "the paper's claim", "label": "cpg-actor-open-loop - cho2019-warm, "
                  "return", "test": st.WELCH, "difference": difference, "log": False, "p": p,
                  "minimum": RELATIVE_EFFECT * abs(float(np.nanmean(cho)))})  # fmt: skip
    f.judge(tests)

    print("# fresh-2M: the analysis of `PROTOCOL.md`\n")
    print(
        "Made by `PYTHONPATH=src python docs/results/fresh-2M/analysis.py "
        + " ".join(sys.argv[1:])
        + "`. Seeds per variant: "
        + ", ".join(f"`{v}` {summary['variants'][v]['seeds']}" for v in VARIANTS)
        + ".\n"
    )
    print(
        f"One family of {len(tests)} tests, {st.family_text(len(tests))}; a difference "
        "counts when its Holm p < 0.05 and it is at least its minimum effect (return and "
        f"hop apex {RELATIVE_EFFECT:.0%} of the other side's mean, retention "
        f"{RETENTION_EFFECT}, smoothness and torque rate a factor {RATIO_EFFECT}, tested on "
        "the logarithm, so ranked and shown by their geometric mean). Means with 95 % "
        "percentile-bootstrap CIs over seeds (display only).\n"
    )
    for name, (_, higher, log) in METRICS.items():
        print(f"## {name} ({'higher' if higher else 'lower'} is better)\n")
        kind = "geometric mean" if log else "mean"
        print(f"| variant | {kind} [95 % CI] | per seed |\n| --- | ---: | --- |")
        for v in VARIANTS:
            ci = f.mean_ci(data[name][v], log)
            seeds = ", ".join(st.three_figures(x) for x in data[name][v])
            print(f"| `{v}`{' (best)' if v == best[name] else ''} | {ci} | {seeds} |")
        group = [t for t in tests if t["group"] == name]
        beaten = [t for t in group if t["passed"]]
        tied = [t["label"].split(" vs ")[1] for t in group if not t["passed"]]
        print()
        verdict = (f"**Pick `{best[name]}`**: it beats every other variant." if not tied else
                   f"`{best[name]}` has the best mean; not separated from "
                   + ", ".join(f"`{v}`" for v in tied)
                   + ("; it beats " + ", ".join(f"`{t['label'].split(' vs ')[1]}`"
                                                for t in beaten) if beaten else "")
                   + ".")  # fmt: skip
        print(verdict + "\n")
    print("## Every test\n")
    print(
        "The last column: yes, the difference counts; reversed, the other side is ahead by "
        "at least the minimum with Holm p < 0.05; no, neither.\n"
    )
    print("\n".join(f.table(tests)))
    print("\n## The CPG-Actor against its start (per seed, `cpg-actor eval`, 5 episodes)\n")
    print("| seed | start return | end return | start apex (m) | end apex (m) |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for i, seed in enumerate(starts["seeds"]):
        print(
            f"| {seed} | {starts['start_return'][i]:.1f} | {starts['end_return'][i]:.1f} | "
            f"{starts['start_apex'][i]:.3f} | {starts['end_apex'][i]:.3f} |"
        )
    matched = matched_smoothness(summary, args.smooth) if args.smooth else []
    if matched:
        print_matched(matched)
    if args.figure:
        figure(data, matched, args.figure)
    atomic_write_text(json.dumps({"data": data, "starts": starts, "tests": tests, "best": best,
                                  "matched_smoothness": matched}, indent=1) + "\n",
                      args.out / "analysis.json")  # fmt: skip


if __name__ == "__main__":
    sys.exit(run_script(main, "fresh-2M/analysis.py"))  # a missing or damaged input: one line
