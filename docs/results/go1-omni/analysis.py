"""The analysis that `PROTOCOL.md` fixes (and `../anymal-omni/PROTOCOL.md`, the same on
ANYmal B), from the folder its commands fill: per grid metric the variant with the best
geometric mean against the 2 others (10 tests) and the CPG-Actor against its start (2 paired
tests), one family, Holm-corrected; the issue's targets per variant; the time to walk, a
family of its own (1 test).

    PYTHONPATH=src python docs/results/go1-omni/analysis.py results/go1-omni \\
        --time-to-walk docs/results/go1-omni/time_to_walk_grid.json \\
        > docs/results/go1-omni/analysis.md

Reads ``OUT/grid/VARIANT/seedS/grid.json`` (``cpg-actor eval --grid``; ``start`` the CPG-Actor's
start) and ``OUT/other/VARIANT/seedS.md`` (``benchmarks/other_model.py``'s report, whose JSON
block holds every episode); writes ``OUT/analysis.json`` (every per-seed value and test).
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
from cpg_actor.inputs import parse_json, read_json, read_text, run_script
from cpg_actor_studies import family as f

VARIANTS = ("cpg-actor", "mlp-field", "mlp-warm-field")
GRID_FILE = "cpg-actor eval --grid's output"  # what a grid.json is, for a message
START = "start"  # the CPG-Actor's checkpoint before its first update
# name: grid key; every one lower is better, tested on its logarithm
METRICS = {
    "linear-velocity error (m/s)": "lin_vel_error",
    "yaw-rate error (rad/s)": "yaw_rate_error",
    "torque rate (N m/s)": "torque_rate",
    "foot slip (m/s)": "foot_slip",
    "planar cost of transport": "planar_cost_of_transport",
}
# display only (PROTOCOL.md: "the offsets stay in the grid files, for the README"): the error of
# each command's mean velocity, without the per-step sway of a gait the per-step errors include
OFFSETS = {
    "linear-velocity offset (m/s)": "lin_vel_offset",
    "yaw-rate offset (rad/s)": "yaw_rate_offset",
}
RATIO_EFFECT = 1.25
TARGETS = {"lin_vel_error": 0.10, "yaw_rate_error": 0.20}  # the flat grid's, per step
OTHER_MODEL_TARGET = 0.15  # m/s at each forward command
TIME_TO_WALK_FACTOR = 5.0  # mlp-field's wall time over cpg-actor's
TIMED = ("cpg-actor", "mlp-field")


def grid_of(out: Path, variant: str) -> list[dict[str, Any]]:
    """Per seed (in order), its ``grid.json``; SystemExit naming what is missing."""
    folders = sorted((out / "grid" / variant).glob("seed*"),
                     key=lambda p: int(p.name.removeprefix("seed")))  # fmt: skip
    if len(folders) < 2:
        sys.exit(f"{out / 'grid' / variant}: 2 or more seedS/grid.json needed, found "
                 f"{len(folders)} (`cpg-actor eval RUN --grid`, as PROTOCOL.md says)")  # fmt: skip
    grids = [read_json(p / "grid.json", GRID_FILE, nulls_as_nan=True) for p in folders]
    for grid, p in zip(grids, folders, strict=True):
        grid.setdefault("seed", int(p.name.removeprefix("seed")))
    return grids


def same_seeds(grids: dict[str, list[dict[str, Any]]]) -> list[int]:
    """The seeds every variant (and the start) was evaluated on; SystemExit where they differ
    (the paired tests pair by seed)."""
    seeds = {v: [g["seed"] for g in grids[v]] for v in grids}
    if len({tuple(s) for s in seeds.values()}) != 1:
        sys.exit("the grid evaluations cover other seeds per variant: "
                 + "; ".join(f"{v} {s}" for v, s in seeds.items())
                 + " (every variant and the start need the same seeds)")  # fmt: skip
    return seeds[VARIANTS[0]]


def flat_means(grid: dict[str, Any]) -> dict[str, float]:
    """The grid's means over its commands on flat ground."""
    return grid["means"]["flat"]


def check_row(grid: dict[str, Any], prefix: str) -> dict[str, Any]:
    return next(row for row in grid["rows"] if row["check"].startswith(prefix))


def other_model(out: Path, variant: str) -> dict[str, Any]:
    """Per seed, ``other_model.py``'s episodes (model -> command -> episodes), from its report's
    JSON block; empty where it has not run."""
    found = {}
    for path in sorted((out / "other" / variant).glob("seed*.md")):
        text = read_text(path, "benchmarks/other_model.py's report")
        if "```json\n" not in text:
            sys.exit(f"{path}: no JSON block (not a report of benchmarks/other_model.py)")
        block = text.split("```json\n", 1)[1].split("\n```", 1)[0]
        found[int(path.stem.removeprefix("seed"))] = parse_json(block, path, "its JSON block")
    return found


def tests_of(data: dict[str, dict[str, list[float]]]) -> tuple[list[dict[str, Any]], dict]:
    tests, best = [], {}
    for name in METRICS:
        variants = {v: data[name][v] for v in VARIANTS}
        best[name], group = f.best_against_others(variants, name, False, True,
                                                  lambda _: math.log(RATIO_EFFECT))  # fmt: skip
        tests += group
    for name in list(METRICS)[:2]:
        end, start = np.log(data[name]["cpg-actor"]), np.log(data[name][START])
        difference, p = st.paired_t_test(start, end)  # > 0: the trained CPG-Actor is lower
        tests.append({"group": "cpg-actor beyond its start", "label": name, "test": st.PAIRED,
                      "difference": difference, "log": True, "p": p,
                      "minimum": math.log(RATIO_EFFECT)})  # fmt: skip
    return f.judge(tests), best


def targets(grids: dict[str, list[dict]], others: dict[str, dict]) -> dict[str, dict[str, Any]]:
    """Per variant, each target's numbers and whether it is met."""
    result = {}
    for v in (*VARIANTS, START):
        means = [flat_means(g) for g in grids[v]]
        entry: dict[str, Any] = {}
        for key, limit in TARGETS.items():
            values = [x[key] for x in means]
            ci = f.mean_ci(values)
            entry[key] = {"ci": [ci.low, ci.high] if ci else None, "per_seed": values,
                          "mean": float(np.mean(values)), "limit": limit,
                          "met": bool(np.mean(values) <= limit)}  # fmt: skip
        grid_falls = [x["fell"] for x in means]
        entry["grid_falls"] = {"per_seed": grid_falls, "met": all(x == 0 for x in grid_falls)}
        payload = [check_row(g, "payload")["fell"] for g in grids[v]]
        entry["payload_falls"] = {"per_seed": payload, "met": all(x == 0 for x in payload)}
        pushes = {side: [check_row(g, f"push {side}") for g in grids[v]]
                  for side in ("left", "right")}  # fmt: skip
        entry["pushes"] = {side: {"falls": [r["fell"] for r in rows],
                                  "recovered": [r.get("recovered", math.nan) for r in rows],
                                  "recovery_seconds": [r.get("recovery_seconds", math.nan)
                                                       for r in rows]}
                           for side, rows in pushes.items()}  # fmt: skip
        if others.get(v):
            per_command = {}
            for seed_runs in others[v].values():
                for command, episodes in seed_runs["other"].items():
                    per_command.setdefault(command, []).append(episodes)
            other = {}
            for command, seeds in per_command.items():
                errors = [float(np.mean([e["speed_error"] for e in eps])) for eps in seeds]
                falls = sum(e["fell"] for eps in seeds for e in eps)
                other[command] = {"per_seed": errors, "mean": float(np.mean(errors)),
                                  "falls": int(falls)}  # fmt: skip
            entry["other_model"] = {
                "commands": other,
                "met": all(
                    c["mean"] <= OTHER_MODEL_TARGET and c["falls"] == 0 for c in other.values()
                ),
            }
        result[v] = entry
    return result


def walk_time(run: dict[str, Any], key: str) -> float:
    """A run's wall time or env steps to the grid target, its start included (a run that missed
    it: at its last evaluation, an underestimate). Met before the first update (the prior
    already walks): counted at the next evaluation's, so that no time is 0 (a log needs it > 0;
    this overstates the faster agent's time, never its lead)."""
    value = run[f"start_{key}"] + run[key]
    if value <= 0 and len(run["history"]) > 1:
        value = run[f"start_{key}"] + run["history"][1][key]
    if not value > 0:
        sys.exit(f"{run['agent']} seed {run['seed']}: no positive {key} to the target")
    return float(value)


def time_to_walk(paths: list[Path]) -> dict[str, Any] | None:
    """Per timed agent its wall times and env steps to the grid target (the start included), and
    the 1-test family: ``mlp-field``'s mean log wall time above ``cpg-actor``'s by more than
    log 5 (Welch, the CPG-Actor's times scaled by 5; counted when Holm p < 0.05 and above)."""
    if not paths:
        return None
    runs = [run for path in paths
            for run in read_json(path, "benchmarks/time_to_walk.py's JSON", kind=list)]  # fmt: skip
    times = {a: {"seeds": [r["seed"] for r in runs if r["agent"] == a],
                 "wall": [walk_time(r, "wall") for r in runs if r["agent"] == a],
                 "steps": [walk_time(r, "steps") for r in runs if r["agent"] == a],
                 "reached": [bool(r["reached"]) for r in runs if r["agent"] == a],
                 "machines": sorted({r.get("machine", "not recorded") for r in runs
                                     if r["agent"] == a})}
             for a in TIMED}  # fmt: skip
    if any(len(times[a]["wall"]) < 2 for a in TIMED):
        sys.exit(f"{', '.join(map(str, paths))}: 2 or more runs of each of {TIMED} needed")
    cpg, mlp = (np.log(times[a]["wall"]) for a in TIMED)
    difference, p = st.welch_test(mlp, cpg + math.log(TIME_TO_WALK_FACTOR))
    label = f"mlp-field / cpg-actor wall time above {TIME_TO_WALK_FACTOR:g}x"
    test = {
        "group": "time to walk",
        "label": label,
        "test": st.WELCH,
        "difference": difference,
        "log": True,
        "p": p,
        "minimum": 0.0,
    }
    f.judge([test])
    ratio = math.exp(float(np.mean(mlp) - np.mean(cpg)))
    return {"times": times, "ratio": ratio, "met": ratio >= TIME_TO_WALK_FACTOR, "test": test}


def shown(values: list[float]) -> str:
    return ", ".join(st.three_figures(x) for x in values)


def report(data, offsets, tests, best, goals, walk, seeds, name: str) -> None:
    print(f"# {name}: the analysis of `PROTOCOL.md`\n")
    print("Made by `PYTHONPATH=src python docs/results/go1-omni/analysis.py "
          f"{' '.join(sys.argv[1:])}`. Seeds: " + ", ".join(f"`{v}` {seeds[v]}" for v in seeds)
          + ".\n")  # fmt: skip
    print(f"One family of {len(tests)} tests, {st.family_text(len(tests))}; a difference "
          f"counts when its Holm p < 0.05 and it is at least a factor {RATIO_EFFECT} (tested on "
          "the logarithm, so ranked and shown by geometric means). Means with 95 % "
          "percentile-bootstrap CIs over seeds (display only).\n")  # fmt: skip
    for name in METRICS:
        print(f"## {name} (lower is better)\n")
        print("| variant | geometric mean [95 % CI] | per seed |\n| --- | ---: | --- |")
        for v in (*VARIANTS, START):
            if data[name].get(v):
                label = f"`{v}`" if v != START else "the CPG-Actor's start"
                mark = " (best)" if v == best[name] else ""
                print(f"| {label}{mark} | {f.mean_ci(data[name][v], True)} | "
                      f"{shown(data[name][v])} |")  # fmt: skip
        group = [t for t in tests if t["group"] == name]
        tied = [t["label"].split(" vs ")[1] for t in group if not t["passed"]]
        print("\n" + (f"**Pick `{best[name]}`**: it beats both others." if not tied else
                      f"`{best[name]}` has the best mean; not separated from "
                      + ", ".join(f"`{v}`" for v in tied) + ".") + "\n")  # fmt: skip
    print("## Offsets of the mean velocity (display only, not tested)\n")
    print("| variant | " + " | ".join(f"{name}, mean [95 % CI]" for name in OFFSETS) + " |")
    print("| --- |" + " ---: |" * len(OFFSETS))
    for v, values in offsets.items():
        label = f"`{v}`" if v != START else "the CPG-Actor's start"
        print(f"| {label} | " + " | ".join(f"{f.mean_ci(values[k])} ({shown(values[k])})"
                                           for k in OFFSETS.values()) + " |")  # fmt: skip
    print("\n## The issue's targets\n")
    print(
        "| variant | grid lin vel error <= 0.10 | grid yaw-rate error <= 0.20 | no fall on "
        "the grid | payload 115 %: no fall | other model <= 0.15 m/s, no fall |"
    )
    print("| --- | --- | --- | --- | --- | --- |")
    for v, goal in goals.items():

        def cell(entry):
            low, high = entry["ci"] or (math.nan, math.nan)
            return (f"{'met' if entry['met'] else 'missed'} ({entry['mean']:.3f} "
                    f"[{low:.3f}, {high:.3f}])")  # fmt: skip

        other = goal.get("other_model")
        other_text = ("not run" if other is None else ("met" if other["met"] else "missed")
                      + " (" + ", ".join(f"{c} m/s: {x['mean']:.3f}, {x['falls']} falls"
                                         for c, x in other["commands"].items()) + ")")  # fmt: skip
        label = "the CPG-Actor's start" if v == START else f"`{v}`"
        print(f"| {label} | {cell(goal['lin_vel_error'])} | {cell(goal['yaw_rate_error'])} | "
              f"{'met' if goal['grid_falls']['met'] else 'missed'} "
              f"({shown(goal['grid_falls']['per_seed'])}) | "
              f"{'met' if goal['payload_falls']['met'] else 'missed'} "
              f"({shown(goal['payload_falls']['per_seed'])}) | {other_text} |")  # fmt: skip
    print("\n## Pushes of 1 m/s (per seed: share fallen, share recovered, recovery time)\n")
    for v, goal in goals.items():
        for side, push in goal["pushes"].items():
            print(f"* `{v}`, {side}: falls {shown(push['falls'])}; recovered "
                  f"{shown(push['recovered'])}; recovery (s) "
                  f"{shown(push['recovery_seconds'])}")  # fmt: skip
    if walk is not None:
        print("\n## Time to walk (a family of its own)\n")
        for a, t in walk["times"].items():
            print(f"* `{a}`: wall time {f.mean_ci(t['wall'], True)} s (geometric mean), env "
                  f"steps {f.mean_ci(t['steps'], True)}, at the target "
                  f"{sum(t['reached'])}/{len(t['reached'])} (seeds {t['seeds']}; on "
                  f"{', '.join(t['machines'])})")  # fmt: skip
        print(f"\nRatio `mlp-field` / `cpg-actor`: {walk['ratio']:.2f} (target >= "
              f"{TIME_TO_WALK_FACTOR:g}: {'met' if walk['met'] else 'missed'}); test: "
              f"{walk['test']['verdict']} (Holm p {walk['test']['adjusted']:.2g}).")  # fmt: skip
    print("\n## Every test\n")
    print("\n".join(f.table(tests)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="the folder of PROTOCOL.md's commands")
    parser.add_argument("--time-to-walk", type=Path, nargs="*", default=[],
                        help="time_to_walk.py's JSON (several: the sittings' parts)")  # fmt: skip
    args = parser.parse_args()
    grids = {v: grid_of(args.out, v) for v in (*VARIANTS, START)}
    same_seeds(grids)
    data = {name: {v: [flat_means(g)[key] for g in grids[v]] for v in grids}
            for name, key in METRICS.items()}  # fmt: skip
    tests, best = tests_of(data)
    goals = targets(grids, {v: other_model(args.out, v) for v in VARIANTS})
    walk = time_to_walk(args.time_to_walk)
    offsets = {v: {key: [flat_means(g)[key] for g in grids[v]] for key in OFFSETS.values()}
               for v in grids}  # fmt: skip
    seeds = {v: [g["seed"] for g in grids[v]] for v in grids}
    report(data, offsets, tests, best, goals, walk, seeds, args.out.resolve().name)
    atomic_write_text(json.dumps({"data": data, "tests": tests, "best": best, "targets": goals,
                                  "offsets": offsets, "time_to_walk": walk}, indent=1) + "\n",
                      args.out / "analysis.json")  # fmt: skip


if __name__ == "__main__":
    sys.exit(run_script(main, "go1-omni/analysis.py"))  # a missing or damaged input: one line
