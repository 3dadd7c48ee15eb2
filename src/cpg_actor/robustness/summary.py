"""The suite's results per variant, over its seeds, and the files: ``robustness.json`` (every
run's numbers and the summary), ``robustness.md`` (a table per perturbation) and a figure per
perturbation (``robustness_<name>.png``: the return retained against the level, a line per
variant with its bootstrap 95% CI band over seeds).

The physical metrics (:data:`PHYSICAL_COLUMNS`) appear where the runs' traces define them (a
``robustness.json`` written before them has none: its tables show none).

Over seeds (as the reproduction report): the mean of the per-seed values, with a percentile
bootstrap CI from :data:`~cpg_actor.statistics.MIN_SEEDS` seeds on
(:func:`cpg_actor.statistics.bootstrap`); a push's recovery as the share of episodes
that recovered and the median steps of those that did.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from cpg_actor import statistics as st
from cpg_actor.robustness.suite import NO_GAIT, NOT_RECOVERED
from cpg_actor.robustness.verdicts import (
    JSON_FILE,
    MARKDOWN_FILE,
    verdict_lines,
    verdict_more_robust,
    verdict_rule,
)

# a variant trained with env.randomize is named as the nominal one with this suffix: the
# verdicts compare the two
RANDOMIZED = "-randomized"
# the physical metrics a level's table shows (:mod:`cpg_actor.metrics.physical`), where
# a run has them; the hop apex's fraction of the nominal one first
PHYSICAL_COLUMNS = ("apex_retention", "hop_apex", "joint_smoothness", "torque_rate",
                    "mechanical_power", "foot_slip", "time_at_joint_stop")  # fmt: skip


def figure_name(perturbation: str) -> str:
    return f"robustness_{perturbation}.png"


def interval(values: list[float]) -> dict[str, float] | None:
    """Mean over seeds with its bootstrap 95% CI (``low``, ``high`` NaN below MIN_SEEDS
    seeds); None without a finite value."""
    finite = st.finite(values)
    if finite.size == 0:
        return None
    if finite.size < st.MIN_SEEDS:
        return {"estimate": float(finite.mean()), "low": math.nan, "high": math.nan}
    ci = st.bootstrap(finite, "mean")
    return {"estimate": ci.estimate, "low": ci.low, "high": ci.high}


def _recovery(episodes: list[float | str]) -> tuple[float, float]:
    """(share recovered of the episodes with a gait, median steps of those recovered)."""
    gait = [e for e in episodes if e != NO_GAIT]
    steps = [float(e) for e in gait if e != NOT_RECOVERED]
    share = len(steps) / len(gait) if gait else math.nan
    return share, float(np.median(steps)) if steps else math.nan


def summarise(runs: list[dict[str, Any]], metrics: tuple[str, ...]) -> dict[str, Any]:
    """Per variant (in the order of ``runs``): its seeds, the nominal numbers and, per
    perturbation and level, the retention, return, metrics, p99 |desired velocity| and (for
    pushes) recovery, each as :func:`interval` over seeds."""
    variants: dict[str, list[dict[str, Any]]] = {}
    for run in runs:
        variants.setdefault(run["variant"], []).append(run)
    keys = ("return", *metrics, "p99_desired_velocity",
            *(key for key in PHYSICAL_COLUMNS if key != "apex_retention"))  # fmt: skip
    out: dict[str, Any] = {}
    for variant, group in variants.items():
        nominal = {key: interval([r["nominal"].get(key, math.nan) for r in group])
                   for key in keys}  # fmt: skip
        perturbations: dict[str, Any] = {}
        for name, axis in group[0]["perturbations"].items():
            levels = []
            for i, level in enumerate(axis["levels"]):
                rows = [r["perturbations"][name]["levels"][i] for r in group
                        if name in r["perturbations"]]  # fmt: skip
                entry = {"level": level["level"]}
                for key in ("retention", "apex_retention", *keys):
                    entry[key] = interval([row.get(key, math.nan) for row in rows])
                if "recovery" in level:
                    shares, steps = zip(*(_recovery(row["recovery"]) for row in rows),
                                        strict=True)  # fmt: skip
                    entry["recovered"] = interval(list(shares))
                    entry["recovery_steps"] = interval(list(steps))
                levels.append(entry)
            perturbations[name] = {key: axis[key] for key in ("field", "unit", "description",
                                                              "nominal")}  # fmt: skip
            perturbations[name]["levels"] = levels
        out[variant] = {"seeds": [r["seed"] for r in group], "nominal": nominal,
                        "perturbations": perturbations}  # fmt: skip
    return out


def retention_scores(runs: list[dict[str, Any]], variant: str, name: str) -> list[float]:
    """Per seed of ``variant``: the mean over perturbation ``name``'s levels of the return
    retained."""
    scores = []
    for run in runs:
        if run["variant"] != variant or name not in run["perturbations"]:
            continue
        values = [level.get("retention") for level in run["perturbations"][name]["levels"]]
        finite = st.finite([math.nan if v is None else v for v in values])
        scores.append(float(finite.mean()) if finite.size else math.nan)
    return scores


def verdict_pairs(variants: list[str]) -> list[tuple[str, str]]:
    """The claims judged: the CPG-Actor more robust than the MLP, and each variant trained
    with randomisation (``NAME-randomized``) more robust than its nominal training (NAME)."""
    pairs = [("cpg-actor", "mlp")] if {"cpg-actor", "mlp"} <= set(variants) else []
    pairs += [(v, v.removesuffix(RANDOMIZED)) for v in variants
              if v.endswith(RANDOMIZED) and v.removesuffix(RANDOMIZED) in variants]  # fmt: skip
    return pairs


def verdicts(runs: list[dict[str, Any]], names: list[str]) -> list[dict[str, Any]]:
    """Per claim (:func:`verdict_pairs`) and perturbation: its verdict and explanation
    (:func:`cpg_actor.robustness.verdicts.verdict_more_robust`), all of them one family
    (:func:`cpg_actor.statistics.decide`: Welch's t-tests, Holm-corrected), with the
    test, its p, its Holm p and the family's size."""
    variants = list(dict.fromkeys(run["variant"] for run in runs))
    rows, claims = [], []
    for first, second in verdict_pairs(variants):
        for name in names:
            claims.append(verdict_more_robust(retention_scores(runs, first, name),
                                              retention_scores(runs, second, name),
                                              (first, second)))  # fmt: skip
            rows.append({"claim": f"{first} more robust than {second}", "perturbation": name})
    family = sum(len(claim.tests) for claim in claims if claim.fixed is None)
    for row, claim, (verdict, why) in zip(rows, claims, st.decide(claims), strict=True):
        row.update(verdict=verdict, why=why, family=family)
        if claim.fixed is None:
            (test,) = claim.tests
            row.update(test=test.name, p=test.p, p_holm=test.adjusted)
    return rows


def plain(value: Any) -> Any:
    """``value`` for JSON: NaN and infinities as null, numpy numbers as Python's."""
    if isinstance(value, dict):
        return {key: plain(v) for key, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def write_json(path: Path, data: dict[str, Any]) -> Path:
    from cpg_actor.files import atomic_write_text

    atomic_write_text(json.dumps(plain(data), indent=1) + "\n", path)
    return path


def _text(entry: dict[str, float] | None, digits: str = ".3g", scale: float = 1.0,
          suffix: str = "") -> str:  # fmt: skip
    if entry is None or entry.get("estimate") is None or not math.isfinite(entry["estimate"]):
        return "—"
    text = f"{scale * entry['estimate']:{digits}}{suffix}"
    low, high = entry.get("low"), entry.get("high")
    if low is not None and high is not None and math.isfinite(low) and math.isfinite(high):
        text += f" [{scale * low:{digits}}, {scale * high:{digits}}]"
    return text


def markdown(data: dict[str, Any]) -> str:
    """``robustness.md``: what was run, then one table per perturbation."""
    from cpg_actor.plots import label
    from cpg_actor.robots.registry import all_metrics

    info = all_metrics()
    metrics = data["metrics"]
    variants = data["variants"]
    lines = [
        "# Robustness",
        "",
        f"Robot: {data['robot']}. Each run's final policy evaluated deterministically "
        f"({data['episodes']} episodes per level, env seed {data['env_seed']}, the same "
        "episodes at every level) nominally and under each perturbation (`cpg-actor "
        "robustness`, docs/robustness.md). *Retention*: mean return / nominal mean return, per "
        "run; per variant the mean over its seeds with a bootstrap 95% CI (from "
        f"{st.MIN_SEEDS} seeds on). *Recovery* (pushes): the share of episodes whose gait "
        f"cycle ({data['cycle']}) came back within 10% of the same episode's without the push, "
        "and the median control steps it took.",
        "",
        "| variant | seeds | nominal return |",
        "| --- | --- | --- |",
    ]
    for variant, summary in variants.items():
        lines.append(f"| {label(variant)} | {len(summary['seeds'])} | "
                     f"{_text(summary['nominal']['return'], '.1f')} |")  # fmt: skip
    if data.get("verdicts"):
        lines += ["", "## Verdicts", "",
                  *verdict_rule(data), *verdict_lines(data)]  # fmt: skip
    names = list(next(iter(variants.values()))["perturbations"]) if variants else []
    physical = physical_columns(variants)
    if "hop_apex" in physical:
        lines += ["", "*Hop apex*: per episode the median over its flights of the highest hip "
                  "height in each (a flight a push came in left out; docs/reproduction.md, "
                  "*Physical metrics*), where the hop height is the episode's highest hip, "
                  "which a push up or a slip raises; *apex kept*: its fraction of the nominal "
                  "one."]  # fmt: skip
    for name in names:
        axis = next(iter(variants.values()))["perturbations"][name]
        unit = f" ({axis['unit']})" if axis["unit"] else ""
        push = any("recovered" in level for level in axis["levels"])
        heads = ["variant", f"level{unit}", "return", "retention"]
        heads += [info[key].column if key in info else key for key in metrics]
        heads += ["p99 \\|v_d\\| (rad/s)"]
        heads += [PHYSICAL_HEADS.get(key) or info_column(key) for key in physical]
        heads += ["recovered", "recovery (steps)"] if push else []
        lines += ["", f"## {name}: {axis['description']}", "",
                  "| " + " | ".join(heads) + " |", "|" + " --- |" * len(heads)]  # fmt: skip
        for variant, summary in variants.items():
            nominal = summary["nominal"]
            cells = [label(variant), f"{axis['nominal']:g} (nominal)",
                     _text(nominal["return"], ".1f"), "100%"]  # fmt: skip
            cells += [_text(nominal.get(key)) for key in metrics]
            cells += [_text(nominal["p99_desired_velocity"], ".1f")]
            cells += ["100%" if key == "apex_retention" else _physical_text(nominal, key)
                      for key in physical]  # fmt: skip
            cells += ["", ""] if push else []
            lines.append("| " + " | ".join(cells) + " |")
            for level in summary["perturbations"][name]["levels"]:
                cells = ["", f"{level['level']:g}", _text(level["return"], ".1f"),
                         _text(level["retention"], ".0f", 100.0, "%")]  # fmt: skip
                cells += [_text(level.get(key)) for key in metrics]
                cells += [_text(level["p99_desired_velocity"], ".1f")]
                cells += [_physical_text(level, key) for key in physical]
                if push:
                    cells += [_text(level["recovered"], ".0f", 100.0, "%"),
                              _text(level["recovery_steps"], ".0f")]  # fmt: skip
                lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


PHYSICAL_HEADS = {"apex_retention": "apex kept"}
PERCENT = ("apex_retention", "time_at_joint_stop")  # shown in %


def _physical_text(row: dict[str, Any], key: str) -> str:
    if key in PERCENT:
        return _text(row.get(key), ".0f" if key == "apex_retention" else ".1f", 100.0, "%")
    return _text(row.get(key))


def info_column(key: str) -> str:
    from cpg_actor.metrics.physical import METRICS

    return METRICS[key].column if key in METRICS else key


def physical_columns(variants: dict[str, Any]) -> list[str]:
    """The :data:`PHYSICAL_COLUMNS` some variant has a value of, nominally or at a level
    (none for a file written before the physical metrics)."""

    def has(entry: Any) -> bool:
        return isinstance(entry, dict) and entry.get("estimate") is not None

    found = set()
    for summary in variants.values():
        rows = [summary["nominal"], *(level for axis in summary["perturbations"].values()
                                      for level in axis["levels"])]  # fmt: skip
        found |= {key for key in PHYSICAL_COLUMNS for row in rows if has(row.get(key))}
    return [key for key in PHYSICAL_COLUMNS if key in found]


def draw(data: dict[str, Any], out: Path) -> list[Path]:
    """A figure per perturbation: retention against the level, a line per variant, the
    nominal point at 1, a band for its CI over seeds."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from cpg_actor.plots import color, label, save_figure

    variants = data["variants"]
    paths = []
    names = list(next(iter(variants.values()))["perturbations"]) if variants else []
    for name in names:
        fig, ax = plt.subplots(figsize=(5.5, 3.8))
        axis = None
        for variant, summary in variants.items():
            axis = summary["perturbations"][name]
            points = [(axis["nominal"], 1.0, 1.0, 1.0)]
            for level in axis["levels"]:
                r = level["retention"] or {}
                ci = [np.nan if r.get(k) is None else r[k] for k in ("estimate", "low", "high")]
                points.append((level["level"], *ci))
            x, y, low, high = (np.array(v, dtype=float) for v in zip(*sorted(points),
                                                                      strict=True))  # fmt: skip
            line = ax.plot(x, y, "o-", label=label(variant), color=color(variant))[0]
            if np.isfinite(low).any():
                ax.fill_between(x, low, high, color=line.get_color(), alpha=0.2, lw=0)
        unit = f" ({axis['unit']})" if axis and axis["unit"] else ""
        ax.axhline(1.0, color="0.6", lw=0.8, ls=":")
        ax.set_xlabel(f"{name}{unit}")
        ax.set_ylabel("return retained (of nominal)")
        ax.set_title(f"{data['robot']}: {name}", fontsize=10)
        ax.legend(fontsize=8)
        fig.tight_layout()
        paths.append(save_figure(fig, out / figure_name(name)))
        plt.close(fig)
    return paths


def write_outputs(out: Path, data: dict[str, Any]) -> list[Path]:
    """``robustness.json``, ``robustness.md`` and the figures in ``out``."""
    from cpg_actor.files import atomic_write_text

    paths = [write_json(out / JSON_FILE, data)]
    atomic_write_text(markdown(plain(data)), out / MARKDOWN_FILE)
    paths.append(out / MARKDOWN_FILE)
    return paths + draw(plain(data), out)


def outputs(out: Path, names: list[str]) -> list[Path]:
    """The files the suite writes in ``out`` for the perturbations ``names``."""
    return [out / JSON_FILE, out / MARKDOWN_FILE, *(out / figure_name(n) for n in names)]
