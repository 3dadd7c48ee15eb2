"""The analysis that `PROTOCOL.md` fixes, from the folder its commands fill: the CPG-Actor
against the field's MLP on rough ground (4 Welch tests) and against its start (1 paired test),
one family, Holm-corrected; the issue's rough-ground target per agent.

    PYTHONPATH=src python docs/results/go1-rough/analysis.py results/go1-rough \\
        [--variants cpg-actor,mlp-field] > docs/results/go1-rough/analysis.md

Reads ``OUT/grid/ROLE/seedS/grid.json`` (``cpg-actor eval --grid --grid-levels 4``; ROLE
``cpg-actor``, ``mlp-field`` or ``start``) and each run's ``OUT/runs/VARIANT/seedS/metrics.jsonl``
(``--variants`` names the two reproduction variants, CPG-Actor first), whose logged terrain
levels it keeps in ``OUT/terrain_levels.json``; a folder without ``runs/`` (this one: run logs
stay out of docs/) is read from that file. Writes ``OUT/analysis.json`` (every per-seed value
and test, and the payload and push rows, shown, not tested).
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
from cpg_actor.inputs import read_json, read_jsonl, run_script
from cpg_actor_studies import family as f

ROLES = ("cpg-actor", "mlp-field")
GRID_FILE = "cpg-actor eval --grid's output"  # what a grid.json is, for a message
START = "start"  # the CPG-Actor's checkpoint before its first update
LEVEL = 4  # the middle of levels 0-9
ROUGH = f"all level {LEVEL}"  # the grid's name for that ground (every kind, the curriculum off)
FALL_TARGET = 0.05  # >= 95 % of the episodes without a fall
ERROR_TARGET = 0.15  # m/s, the linear-velocity error at the level
RATIO_EFFECT = 1.25
FALL_EFFECT = 0.05
LEVEL_EFFECT = 1.0
LAST_LOGGED = 10  # the terrain level reached: the mean of the last logged values
# name: (ground, grid key, tested on the logarithm, minimum effect)
METRICS: dict[str, tuple[str, str, bool, float]] = {
    f"falls at level {LEVEL} (share of episodes)": (ROUGH, "fell", False, FALL_EFFECT),
    f"linear-velocity error at level {LEVEL} (m/s)": (ROUGH, "lin_vel_error", True, RATIO_EFFECT),
    "linear-velocity error on flat ground (m/s)": ("flat", "lin_vel_error", True, RATIO_EFFECT),
}
SHOWN = {  # reported, not tested
    f"yaw-rate error at level {LEVEL} (rad/s)": (ROUGH, "yaw_rate_error"),
    "yaw-rate error on flat ground (rad/s)": ("flat", "yaw_rate_error"),
}
REACHED = "terrain level reached (0-9)"
CHECKS = ("payload", "push left", "push right")  # the grid's rows beyond its commands


def seed_folders(folder: Path, what: str) -> list[Path]:
    folders = sorted(folder.glob("seed*"), key=lambda p: int(p.name.removeprefix("seed")))
    if len(folders) < 2:
        sys.exit(f"{folder}: 2 or more seedS{what} needed, found {len(folders)} (PROTOCOL.md "
                 "says how to make them)")  # fmt: skip
    return folders


def grids_of(out: Path, role: str) -> dict[int, dict[str, Any]]:
    """Per seed, the grid of ``role``; SystemExit naming what is missing."""
    grids = {}
    for folder in seed_folders(out / "grid" / role, "/grid.json"):
        grid = read_json(folder / "grid.json", GRID_FILE, nulls_as_nan=True)
        if ROUGH not in grid["means"] or "flat" not in grid["means"]:
            sys.exit(f"{folder / 'grid.json'}: needs the grounds flat and {ROUGH!r}, has "
                     f"{sorted(grid['means'])} (`--grid --grid-levels {LEVEL}`)")  # fmt: skip
        grids[int(folder.name.removeprefix("seed"))] = grid
    return grids


CURRICULA = "terrain_levels.json"  # per variant, per seed: [env steps, terrain level] as logged


def read_curricula(
    out: Path, variants: tuple[str, ...], keep: bool = True
) -> dict[str, dict[int, list]]:
    """Per variant, per seed, its run's logged ``charts/terrain_level`` with the env steps, from
    ``OUT/runs`` (then, with ``keep``, kept in ``OUT/terrain_levels.json``) or, without runs,
    from that file."""
    if not (out / "runs").is_dir():
        path = out / CURRICULA
        if not path.is_file():
            sys.exit(f"{out}: neither runs/VARIANT/seedS/metrics.jsonl nor {CURRICULA} "
                     "(PROTOCOL.md says how to make them)")  # fmt: skip
        try:
            kept = read_json(path)
            missing = [v for v in variants if v not in kept]
        except (ValueError, TypeError):
            sys.exit(f"{path}: not the terrain levels this analysis keeps (a JSON object of "
                     "variant: seed: [[env steps, level], ...])")  # fmt: skip
        if missing:
            sys.exit(f"{path}: no variant {missing}; it holds {sorted(kept)}")
        return {v: {int(s): rows for s, rows in kept[v].items()} for v in variants}
    curricula: dict[str, dict[int, list]] = {}
    for variant in variants:
        curricula[variant] = {}
        for folder in seed_folders(out / "runs" / variant, "/metrics.jsonl"):
            rows = read_jsonl(folder / "metrics.jsonl", "the metrics cpg-actor train logs")
            levels = [[r.get("global_step"), r["charts/terrain_level"]] for r in rows
                      if isinstance(r.get("charts/terrain_level"), int | float)]  # fmt: skip
            if not levels:
                sys.exit(f"{folder / 'metrics.jsonl'}: no charts/terrain_level logged (a run on "
                         "rough ground with the curriculum logs it)")  # fmt: skip
            curricula[variant][int(folder.name.removeprefix("seed"))] = levels
    if keep:
        atomic_write_text(json.dumps(curricula) + "\n", out / CURRICULA)
    return curricula


def level_reached(levels: dict[int, list]) -> dict[int, float]:
    """Per seed, the mean of the last logged terrain levels of its run."""
    return {seed: float(np.mean([level for _, level in rows[-LAST_LOGGED:]]))
            for seed, rows in levels.items()}  # fmt: skip


def check_row(grid: dict[str, Any], ground: str, check: str, where: str) -> dict[str, Any]:
    """The grid's row of ``check`` (payload, push left, push right) on ``ground``."""
    for row in grid["rows"]:
        if row.get("terrain") == ground and row.get("check", "").startswith(check):
            return row
    sys.exit(f"{where}: no {check!r} row on {ground!r} (`cpg-actor eval --grid` writes one)")


def checks_of(grids: dict[str, dict[int, dict]], order: list[int]) -> dict[str, dict]:
    """Per role, ground and check, the per-seed share of episodes that fell and, after a push,
    that recovered: reported, not tested."""
    result: dict[str, dict] = {}
    for role, by_seed in grids.items():
        for ground in ("flat", ROUGH):
            for check in CHECKS:
                rows = [check_row(by_seed[s], ground, check, f"grid/{role}/seed{s}/grid.json")
                        for s in order]  # fmt: skip
                entry = {"fell": [float(r["fell"]) for r in rows]}
                if check.startswith("push"):
                    entry["recovered"] = [float(r.get("recovered", math.nan)) for r in rows]
                result.setdefault(role, {}).setdefault(ground, {})[check] = entry
    return result


def collect(out: Path, variants: tuple[str, str]) -> tuple[dict, dict, list[int]]:
    """Per metric, per role (and the start), the per-seed values, in the order of the seeds
    every one of them has, and the payload and push rows (`checks_of`); SystemExit where the
    seeds differ (the paired test pairs by seed)."""
    grids = {role: grids_of(out, role) for role in (*ROLES, START)}
    curricula = read_curricula(out, variants)
    reached = {role: level_reached(curricula[v]) for role, v in zip(ROLES, variants, strict=True)}
    seeds = {role: sorted(g) for role, g in grids.items()}
    seeds |= {f"{role} runs": sorted(r) for role, r in reached.items()}
    if len({tuple(s) for s in seeds.values()}) != 1:
        sys.exit("the evaluations and runs cover other seeds: "
                 + "; ".join(f"{k} {s}" for k, s in seeds.items())
                 + " (every agent and the start need the same seeds)")  # fmt: skip
    order = seeds[START]
    data: dict[str, dict[str, list[float]]] = {}
    for name, (ground, key, *_) in {**METRICS, **SHOWN}.items():
        data[name] = {role: [float(grids[role][s]["means"][ground][key]) for s in order]
                      for role in grids}  # fmt: skip
    data[REACHED] = {role: [reached[role][s] for s in order] for role in ROLES}
    return data, checks_of(grids, order), order


def tests_of(data: dict[str, dict[str, list[float]]]) -> list[dict[str, Any]]:
    """The family: the CPG-Actor against the MLP on each tested metric (> 0 favours the
    CPG-Actor), and against its start on the falls at the level; judged together."""
    tests = []
    cpg, mlp = ROLES
    for name, (_, _, log, effect) in {**METRICS, REACHED: ("", "", False, LEVEL_EFFECT)}.items():
        higher = name == REACHED
        a, b = (np.log(data[name][r]) if log else np.asarray(data[name][r]) for r in (cpg, mlp))
        difference, p = st.welch_test(a, b) if higher else st.welch_test(b, a)
        tests.append({"group": name, "label": f"{cpg} vs {mlp}", "test": st.WELCH,
                      "difference": difference, "log": log, "p": p,
                      "minimum": math.log(effect) if log else effect})  # fmt: skip
    falls = next(iter(METRICS))
    difference, p = st.paired_t_test(data[falls][START], data[falls][cpg])  # > 0: falls less
    tests.append({"group": falls, "label": f"{cpg} vs its start", "test": st.PAIRED,
                  "difference": difference, "log": False, "p": p,
                  "minimum": FALL_EFFECT})  # fmt: skip
    return f.judge(tests)


def targets(data: dict[str, dict[str, list[float]]]) -> dict[str, dict[str, Any]]:
    """Per role (and the start), the rough-ground target's two numbers and whether each is met."""
    falls, error = list(METRICS)[:2]
    result = {}
    for role in (*ROLES, START):
        entry = {}
        for key, name, limit in (("falls", falls, FALL_TARGET), ("error", error, ERROR_TARGET)):
            values = data[name][role]
            ci = f.mean_ci(values)
            entry[key] = {"per_seed": values, "mean": float(np.mean(values)), "limit": limit,
                          "ci": [ci.low, ci.high] if ci else None,
                          "met": bool(np.mean(values) <= limit)}  # fmt: skip
        result[role] = entry
    return result


def seeds_text(values: list[float]) -> str:
    """The mean over the seeds with a value, then each seed's ("no gait": none to recover)."""
    known = [x for x in values if math.isfinite(x)]
    mean = f"{np.mean(known):.2f}" if known else "no gait"
    return f"{mean} ({', '.join(f'{x:.2f}' if math.isfinite(x) else 'no gait' for x in values)})"


def label(role: str) -> str:
    return "the CPG-Actor's start" if role == START else f"`{role}`"


def report(data, checks, tests, goals, seeds, variants) -> None:
    print("# go1-rough: the analysis of `PROTOCOL.md`\n")
    print("Made by `PYTHONPATH=src python docs/results/go1-rough/analysis.py "
          f"{' '.join(sys.argv[1:])}`. Seeds {seeds}; runs of the variants "
          f"`{variants[0]}` (CPG-Actor) and `{variants[1]}` (MLP).\n")  # fmt: skip
    print(f"One family of {len(tests)} tests, {st.family_text(len(tests))}; a difference counts "
          f"when its Holm p < 0.05 and it is at least its minimum effect (falls {FALL_EFFECT}, "
          f"errors a factor {RATIO_EFFECT} on the logarithm, the level reached {LEVEL_EFFECT:g} "
          "level). Means with 95 % percentile-bootstrap CIs over seeds (display only; geometric "
          "for the errors).\n")  # fmt: skip
    logged = {name: spec[2] for name, spec in METRICS.items()} | {REACHED: False}
    for name, values in data.items():
        log = logged.get(name, True)
        better = "higher" if name == REACHED else "lower"
        tested = "" if name in logged else ", shown, not tested"
        print(f"## {name} ({better} is better{tested})\n")
        print("| agent | mean [95 % CI] | per seed |\n| --- | ---: | --- |")
        for role, per_seed in values.items():
            shown = ", ".join(st.three_figures(x) for x in per_seed)
            print(f"| {label(role)} | {f.mean_ci(per_seed, log)} | {shown} |")
        print()
    print(f"## The issue's target on rough ground (level {LEVEL})\n")
    print(f"| agent | falls <= {FALL_TARGET} | linear-velocity error <= {ERROR_TARGET} m/s |")
    print("| --- | --- | --- |")
    for role, goal in goals.items():
        cells = []
        for entry in (goal["falls"], goal["error"]):
            low, high = entry["ci"] or (math.nan, math.nan)
            cells.append(f"{'met' if entry['met'] else 'missed'} ({entry['mean']:.3f} "
                         f"[{low:.3f}, {high:.3f}])")  # fmt: skip
        print(f"| {label(role)} | {cells[0]} | {cells[1]} |")
    print("\n## Payload (115 %) and pushes (1 m/s) while walking forward at 0.5 m/s (shown, "
          "not tested)\n")  # fmt: skip
    print("Per seed, the share of the episodes that fell and, after a push, the share that "
          "recovered its gait (\"no gait\": the agent has no periodic gait without the push, "
          "so none to recover); the mean over the seeds first.\n")  # fmt: skip
    print("| agent | ground | check | fell | recovered |\n| --- | --- | --- | --- | --- |")
    for role, grounds in checks.items():
        for ground, rows in grounds.items():
            for check, entry in rows.items():
                recovered = seeds_text(entry["recovered"]) if "recovered" in entry else "-"
                print(f"| {label(role)} | {ground} | {check} | {seeds_text(entry['fell'])} | "
                      f"{recovered} |")  # fmt: skip
    print("\n## Every test\n")
    print("The last column: yes, the first side is ahead by at least the minimum with Holm p < "
          "0.05; reversed, the second side is; no, neither.\n")  # fmt: skip
    print("\n".join(f.table(tests)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="the folder of PROTOCOL.md's commands")
    parser.add_argument("--variants", default=",".join(ROLES),
                        help="the reproduction's two variants, CPG-Actor first "
                        "(default cpg-actor,mlp-field)")  # fmt: skip
    args = parser.parse_args()
    variants = tuple(v.strip() for v in args.variants.split(","))
    if len(variants) != 2 or not all(variants):
        parser.error(f"--variants takes two names, CPG-Actor first, got {args.variants!r}")
    data, checks, seeds = collect(args.out, variants)
    tests = tests_of(data)
    goals = targets(data)
    report(data, checks, tests, goals, seeds, variants)
    atomic_write_text(json.dumps({"seeds": seeds, "variants": variants, "data": data,
                                  "checks": checks, "tests": tests, "targets": goals},
                                 indent=1) + "\n",
                      args.out / "analysis.json")  # fmt: skip


if __name__ == "__main__":
    sys.exit(run_script(main, "go1-rough/analysis.py"))  # a missing or damaged input: one line
