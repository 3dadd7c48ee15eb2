"""``OUT/report.md`` and ``OUT/summary.json``: the numbers (:mod:`~.summary`), the figures
(:mod:`~.figures`) and the paper's claims (:mod:`~.claims`), on the hopper."""

from __future__ import annotations

import json
import os
import platform
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from cpg_actor.api import atomic_write_text, label, physical, signals
from cpg_actor.api import statistics as st
from cpg_actor.machine import cpu_model, git_commit
from cpg_actor.robustness.verdicts import JSON_FILE, MARKDOWN_FILE, verdict_lines, verdict_rule
from cpg_actor_studies.hopper_paper.comparisons import COMPARED
from cpg_actor_studies.hopper_paper.figures import make_figures
from cpg_actor_studies.hopper_paper.floor import FLOOR_FILE, load_floor
from cpg_actor_studies.hopper_paper.summary import (
    DEFAULT_REWARD,
    REWARD_KEYS,
    _reward_terms,
    summarise,
)
from cpg_actor_studies.reproduction import numbers
from cpg_actor_studies.reproduction.plan import STAGE_LABELS, load_settings_file
from cpg_actor_studies.reproduction.results import (
    Results,
)
from cpg_actor_studies.transfer import load_transfer, transfer_lines


def seeds_of(
    summary: dict[str, Any], reward: str | None = None
) -> dict[str, dict[str, list[float]]]:
    """Per-seed numbers per variant (only those trained on ``reward``, if given)."""
    return {
        variant: row["per_seed"]
        for variant, row in summary["variants"].items()
        if reward is None or row.get("reward") == reward
    }


def _floor_reward(floor: dict[str, Any] | None) -> str | None:
    """The reward the floor was computed with, in :func:`reward_of`'s form."""
    if floor is None:
        return None
    env = floor.get("env") or {}
    values = {key: env.get(key, DEFAULT_REWARD[key]) for key in REWARD_KEYS}
    del values["apex_weight"]  # the floor is always eq. 4's reward
    return ", ".join(f"{k}={v}" for k, v in values.items())


def _floor_lines(
    floor: dict[str, Any] | None, seeds: dict[str, dict[str, list[float]]]
) -> list[str]:
    """The open-loop grid floor and which trained variants clear it (CI above it)."""
    if floor is None:
        return []
    best = floor["best_return"]
    value = best["episode_return"]
    described = ", ".join(f"{k} {v:.3g}" for k, v in best["parameters"].items())
    above, below, unresolved, few = [], [], [], []
    tests = []  # (variant, difference, p): one-sample t-tests against the floor, one family
    for variant, per_seed in seeds.items():
        if not st.seeds_with_data(per_seed["final_return"]):
            continue
        if not st.enough_seeds(per_seed["final_return"]):  # no test: listed apart
            few.append(f"`{variant}`")
            continue
        tests.append((variant, *st.one_sample_t_test(per_seed["final_return"], value)))
    minimum = st.MINIMUM_EFFECT["return"].threshold(value)
    adjusted = st.holm([p for *_, p in tests])
    for (variant, difference, _), holm_p in zip(tests, adjusted, strict=True):
        resolved = holm_p < st.ALPHA and abs(difference) >= minimum
        target = (above if difference > 0 else below) if resolved else unresolved
        target.append(f"`{variant}` ({difference:+.0f})")
    few_text = f"; fewer than {st.MIN_SEEDS} seeds, not tested: {', '.join(few)}" if few else ""
    return [
        f"**Open-loop grid floor** (no learning; `{FLOOR_FILE}`): the best of "
        f"{floor['candidates']} constant CPG parameter sets ({described}; a, w at the preset's; "
        f"one episode, no reset noise, eq. 4's reward with this reproduction's env settings) "
        f"returns **{value:.0f}** (hop height p90 {best['hop_height_p90']:.2f} m; the highest "
        f"hopping set: {floor['best_hop']['hop_height_p90']:.2f} m, return "
        f"{floor['best_hop']['episode_return']:.0f}). Final return minus the floor, mean over "
        f"seeds (variants trained on this reward), by a one-sample t-test with the "
        f"{st.family_text(len(tests))} (every variant here) and a minimum effect of "
        f"{st.MINIMUM_EFFECT['return']} (the floor): above it {', '.join(above) or 'none'}; "
        f"below it {', '.join(below) or 'none'}; not resolved {', '.join(unresolved) or 'none'}"
        f"{few_text}.",
        "",
    ]


def _learning_lines(summary: dict[str, Any]) -> list[str]:
    """Was each variant still learning at the end: its best moving mean of logged
    evaluations against its final one, and its exploration std at the end."""
    rows = [
        (variant, row)
        for variant, row in summary["variants"].items()
        if np.isfinite(row["peak_return"][0])
    ]
    if not rows:
        return []
    lines = [
        "## Learning over the run",
        "",
        f"*Peak*: the best mean of {numbers.FINAL_ROWS} consecutive logged evaluations (the final "
        "return is the last such mean) and the step where that window ends, mean over seeds; "
        "*final - peak*: per seed, 0 for a run still at its best at the end. *Std at the end*: "
        "the policy's Gaussian std at the last logged iteration, the mean over the action's "
        "entries of exp(log_std) in the action's units (rad for joint targets; Cho et al.'s "
        "actions are CPG parameters). A run whose std has collapsed explores no more and stops "
        "learning.",
        "",
        "| variant | peak return | peak at (steps) | final return | final - peak | "
        "std at the end |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for variant, row in rows:
        seeds = row["per_seed"]
        drop = np.asarray(seeds["final_return"], float) - np.asarray(seeds["peak_return"], float)
        drop_text = _pm(st.mean_std(list(drop)))
        lines.append(
            f"| {label(variant)} | {_pm(row['peak_return'])} | "
            f"{row['peak_step'][0]:,.0f} | {_pm(row['final_return'])} | {drop_text} | "
            f"{_pm(row['final_std'])} |"
        )
    return lines + [""]


def _comparison_lines(comparisons: list[dict[str, Any]]) -> list[str]:
    if not comparisons:
        return []

    def cell(values: list[float] | None, digits: int) -> str:
        if values is None:
            return "-"
        value, low, high = values
        return f"{value:+.{digits}f} [{low:+.{digits}f}, {high:+.{digits}f}]"

    def p_cell(values: list[float] | None) -> str:
        return "-" if values is None else f"{values[0]:.2g} / {values[1]:.2g}"

    minimum = {name: st.MINIMUM_EFFECT[metric] for _, name, metric in COMPARED}
    lines = [
        "## Comparisons beyond the paper",
        "",
        "First minus second variant: final return (the last logged deterministic evaluations) "
        "and hop height (the last 3 logged evaluations), mean difference over seeds with its "
        f"bootstrap 95% CI (shown). *p*: {st.WELCH} (two-sided) / its p after the "
        f"{st.family_text(comparisons[0]['family'])} (every test of this table). *Better* "
        f"names a variant where the {st.HOLM} p < {st.ALPHA:g} and the difference is at least "
        f"the minimum effect ({minimum['return']} for returns, {minimum['hop']} for hop "
        "heights; the baseline: the second variant's mean).",
        "",
        "| question | first - second | return difference | p (return) | better (return) | "
        "hop height difference (m) | p (hop) | better (hop) |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for row in comparisons:
        lines.append(
            f"| {row['question']} | `{row['first']}` - `{row['second']}` | "
            f"{cell(row['return'], 1)} | {p_cell(row.get('return_p'))} | "
            f"{row['return_better']} | {cell(row['hop'], 3)} | {p_cell(row.get('hop_p'))} | "
            f"{row['hop_better']} |"
        )
    return lines + [""]


def environment() -> dict[str, Any]:
    """Package versions, machine and git commit, for the report."""
    versions = {"python": platform.python_version()}
    for package in (
        "cpg-actor",
        "torch",
        "numpy",
        "mujoco",
        "pybullet",
        "gymnasium",
        "matplotlib",
        "ray",
    ):
        try:
            versions[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            versions[package] = "not installed"
    cpu = cpu_model()
    return {
        "versions": versions,
        "machine": f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}",
        "commit": git_commit(),
    }


def _trained_commits(results: Results) -> str:
    """The commits the runs were trained at, as their markers recorded them."""
    commits = sorted({run.commit for runs in results.runs.values() for run in runs})
    return ", ".join(commits) if commits else "-"


# how the tables of means read: a variant of fewer seeds shows its mean, no spread (never "+- 0")
SPREAD = f"mean +- std over seeds (n < {st.MIN_SEEDS} seeds: the mean alone, no interval)"


def _pm(value: tuple[float, float], digits: int = 3) -> str:
    """Mean +- std; the mean alone where the std is not given (fewer than 3 seeds)."""
    mean, std = value
    if not np.isfinite(mean):
        return "-"
    return f"{mean:.{digits}g}" + (f" +- {std:.2g}" if np.isfinite(std) else "")


def _pct(value: tuple[float, float]) -> str:
    mean, std = value
    if not np.isfinite(mean):
        return "-"
    return f"{100 * mean:.1f}%" + (f" +- {100 * std:.1g}" if np.isfinite(std) else "")


def _seed_cell(row: dict[str, Any], key: str, digits: int = 3, percent: bool = False) -> str:
    """A variant's ``key``: the median over seeds with its bootstrap 95% CI, ``median [low,
    high]``; with fewer than ``MIN_SEEDS`` seeds with data, their values (no interval); "-"
    for none."""

    def text(x: float) -> str:
        return f"{100 * x:.1f}%" if percent else f"{x:.{digits}g}"

    interval = row["median"].get(key)  # a key added after a summary was written: none
    if interval is None:
        return ", ".join(text(x) for x in st.finite(row["per_seed"].get(key))) or "-"
    return f"{text(interval[0])} [{text(interval[1])}, {text(interval[2])}]"


def write_report(out: Path, run_results: list[dict[str, Any]] | None = None) -> Path:
    """Figures, ``summary.json`` and ``report.md`` for the results directory ``out``
    (``run_results``: the runs of the ``cpg-actor reproduce`` that wrote it, if any)."""
    out = Path(out)
    saved = load_settings_file(out) or {}
    settings = saved.get("settings", {})
    variants = list(settings.get("variants") or [])
    results = Results.load(out, variants or None)
    total_steps = int(settings.get("total_steps") or 0) or _longest_run(results)
    figures, notes = make_figures(results)
    notes += [f"{variant}: no run directory" for variant in variants if not results.has(variant)]
    summary = summarise(results, total_steps)
    summary["environment"] = environment()
    summary["notes"] = notes
    atomic_write_text(json.dumps(summary, indent=2, default=str) + "\n", out / "summary.json")
    lines = [
        *_setup_lines(saved, results, total_steps, summary["environment"]),
        *_invocation_lines(run_results or []),
        *_variant_lines(summary, load_floor(out)),
        *physical_lines(summary),
        *_feedback_lines(summary),
        *_reward_term_lines(summary),
        "",
        *_learning_lines(summary),
        *_stage_lines(summary),
        "",
        *_comparison_lines(summary["comparisons"]),
        *transfer_lines(load_transfer(out)),
        *robustness_lines(out),  # the suite's verdicts, if it ran on this reproduction
        *_claim_lines(summary, total_steps),
        *_figure_lines(figures, out),
        *_definition_lines(),
    ]
    if notes:
        lines += ["## Notes", ""] + [f"* {note}" for note in notes] + [""]
    path = out / "report.md"
    atomic_write_text("\n".join(lines), path)
    return path


def _longest_run(results: Results) -> int:
    """The most steps any run logged (the budget of a results directory without settings)."""
    curves = (run.return_curve()[0] for runs in results.runs.values() for run in runs)
    return max((int(steps.max(initial=0)) for steps in curves), default=0)


def _setup_lines(
    saved: dict[str, Any], results: Results, total_steps: int, env: dict[str, Any]
) -> list[str]:
    """The report's title and "Setup": the command, budget, variants, machine and code."""
    settings = saved.get("settings", {})
    variants = list(settings.get("variants") or [])
    return [
        "# CPG-Actor reproduction report",
        "",
        f"Generated {datetime.now(timezone.utc).strftime('%Y-%m-%d %H:%M UTC')} by "
        "`cpg-actor reproduce` / `cpg-actor figures`.",
        "",
        "## Setup",
        "",
        f"* command: `{saved.get('command', '(unknown)')}`",
        f"* budget: **{total_steps:,} control steps per run**, "
        f"{settings.get('seeds', '?')} seed(s) per variant; the paper compares at 20M steps "
        "and shows the progressive hopping at 1M / 20M / 60M steps.",
        f"* variants: {', '.join(variants) if variants else ', '.join(results.runs)}",
        f"* overrides: {', '.join(settings.get('overrides') or []) or 'none'}; "
        f"num_envs {settings.get('num_envs') or 'default'}, "
        f"simulator {settings.get('sim') or 'default (mujoco)'}",
        f"* stage evaluations at fractions {', '.join(STAGE_LABELS)} of the budget, "
        f"{settings.get('eval_episodes', '?')} deterministic episodes each",
        f"* machine: {env['machine']}",
        f"* code: runs trained at cpg-actor commit {_trained_commits(results)}; this report "
        f"rendered at commit {env['commit']}",
        "* versions: " + ", ".join(f"{k} {v}" for k, v in env["versions"].items()),
        "",
    ]


def _invocation_lines(run_results: list[dict[str, Any]]) -> list[str]:
    """The runs of this invocation: how many finished, skipped and failed, and on which Ray
    nodes (none without runs)."""
    if not run_results:
        return []
    failed = [r for r in run_results if r.get("status") == "failed"]
    lines = [
        f"Runs this invocation: {len(run_results)} "
        f"({sum(r['status'] == 'done' for r in run_results)} completed, "
        f"{sum(r['status'] == 'skipped' for r in run_results)} skipped as finished, "
        f"{len(failed)} failed).",
        "",
    ]
    for r in failed:
        lines.append(f"* **failed** {r['name']}: {r.get('error', '')}")
    if failed:
        lines.append("")
    nodes: dict[str, list[str]] = {}
    for r in run_results:
        if r.get("node"):
            node = r["node"]
            key = f"{node['hostname']} ({node['ip']}, node {node['id'][:8]})"
            nodes.setdefault(key, []).append(r["name"])
    if nodes:
        lines += [f"Ray nodes this invocation ({len(nodes)}):", ""]
        lines += [f"* {key}: {', '.join(names)}" for key, names in nodes.items()]
        lines.append("")
    return lines


def _variant_lines(summary: dict[str, Any], floor: Any) -> list[str]:
    """The section "Results per variant": the table of per-seed numbers, the open-loop grid's
    floor and the ratio of the CPG-Actor's return to Cho et al.'s."""
    lines = [
        "## Results per variant",
        "",
        f"Per seed one number; per variant the **median over seeds [its bootstrap 95% CI]** "
        f"({st.RESAMPLES:,} resamples of the seeds); a variant with fewer than {st.MIN_SEEDS} "
        "seeds with data shows its per-seed values instead, with no interval. *Final return*: "
        f"mean of the last {numbers.FINAL_ROWS} deterministic evaluations logged during training "
        "(`eval/return`, the mean return of the policy's mean action over a few episodes on "
        "evaluation envs; runs logged without it: `charts/episode_return`, the mean return of "
        "the last 100 training episodes). The other columns come from the deterministic "
        "evaluation of the final checkpoint: *desired velocity* is, for every agent, the finite "
        "difference of the desired joint positions sent to the env (after its clip to the joint "
        "limits) over the control period; *at a joint stop*: the share of control steps at "
        f"which a desired position sent is within {signals.JOINT_STOP_TOLERANCE:g} rad of its "
        "joint's limit.",
        "",
        "| variant | seeds (finished) | final return | eval return | hop height (m) | "
        "command smoothness (rad^2) | p99 desired \\|v\\| (rad/s) | "
        "desired vel. within +-15 rad/s | time at a joint stop |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for variant, row in summary["variants"].items():
        lines.append(
            f"| {label(variant)} (`{variant}`) | {row['seeds']} ({row['finished']}) | "
            f"{_seed_cell(row, 'final_return')} | {_seed_cell(row, 'eval_return')} | "
            f"{_seed_cell(row, 'hop_height')} | {_seed_cell(row, 'smoothness')} | "
            f"{_seed_cell(row, 'velocity_p99')} | "
            f"{_seed_cell(row, 'velocity_share', percent=True)} | "
            f"{_seed_cell(row, 'time_at_stop', percent=True)} |"
        )
    floor_reward = _floor_reward(floor)
    lines += [""] + _floor_lines(floor, seeds_of(summary, floor_reward))
    if "cpg-actor" in summary["variants"] and "cho2019-warm" in summary["variants"]:
        cpg = summary["variants"]["cpg-actor"]["per_seed"]["return_at_comparison"]
        cho = summary["variants"]["cho2019-warm"]["per_seed"]["return_at_comparison"]
        ratio = st.bootstrap_ratio(cpg, cho) if st.enough_seeds(cpg, cho) else None
        if not st.enough_seeds(cpg, cho):
            text = f"not tested (fewer than {st.MIN_SEEDS} seeds with data on a side)"
        elif ratio is None:
            text = "undefined (Cho et al. (warm) mean return is not positive)"
        else:
            text = str(ratio)
        lines += [
            f"Ratio of mean final returns CPG-Actor / Cho et al. (warm) at "
            f"{summary['comparison_step']:,} steps, with its bootstrap 95% CI over seeds: "
            f"**{text}**.",
            "",
        ]
    return lines


def physical_lines(summary: dict[str, Any]) -> list[str]:
    """The section "Physical metrics": what each variant's robot did in the final
    evaluation (:mod:`cpg_actor.metrics.physical`), a column per metric; "-" where a
    variant's traces lack the data (saved before the metric existed)."""
    columns = [("hop_apex", False), ("hop_height", False), ("joint_smoothness", False),
               ("smoothness", False), ("torque_rate", False), ("mechanical_power", False),
               ("foot_slip", False), ("time_at_joint_stop", True)]  # fmt: skip
    heads = {"hop_height": "highest hip (m)", "smoothness": "command smoothness (rad^2)"}
    heads.update({name: info.column for name, info in physical.METRICS.items()})
    heads["time_at_joint_stop"] = "time at a joint stop (measured)"
    lines = [
        "## Physical metrics",
        "",
        "What the robot did in the deterministic evaluation of the final checkpoint, by the "
        "same code for every agent (docs/reproduction.md, *Physical metrics*); per seed the mean "
        "over its episodes, per variant the median over seeds [bootstrap 95% CI]. *Hop "
        "apex*: per episode the median over its flight phases of the highest hip height in "
        "the flight above the standing one (a flight a push came in left out); *highest hip*: "
        "the episode's maximum (the env's `hop_height`, raised by a push or a slip). "
        "*Joint smoothness*: the mean squared second difference of the measured joint "
        "positions; *command smoothness* the same of the desired positions sent. *Torque "
        "rate*: mean |tau[t] - tau[t-1]| / dt; *mechanical power*: mean sum over joints of "
        "|tau qdot|; *foot slip*: the planted foot's mean horizontal speed; *time at a joint "
        f"stop*: share of steps with a measured joint within {physical.JOINT_STOP_MARGIN:g} rad "
        "of its limit.",
        "",
        "| variant | " + " | ".join(heads[key] for key, _ in columns) + " |",
        "| --- |" + " --- |" * len(columns),
    ]
    for variant, row in summary["variants"].items():
        cells = [_seed_cell(row, key, percent=percent) for key, percent in columns]
        lines.append(f"| {label(variant)} (`{variant}`) | " + " | ".join(cells) + " |")
    return lines + [""]


def _feedback_lines(summary: dict[str, Any]) -> list[str]:
    """The section "CPG signals and feedback", for the variants whose traces have them (none
    else)."""
    feedback_rows = [
        (variant, row)
        for variant, row in summary["variants"].items()
        if np.isfinite(row["xi_at_bound"][0]) or np.isfinite(row["theta_dot_variability"][0])
    ]
    if not feedback_rows:
        return []
    lines = [
        "## CPG signals and feedback",
        "",
        f"From the final evaluation traces, {SPREAD}: the standard deviation "
        "over an episode (after 50 steps) of theta_dot and r_ddot (how much the CPG "
        "responds), and for bounded feedback the share of xi and kappa values at 95 % or "
        "more of their bound (near 100 %: bang-bang feedback).",
        "",
        "| variant | std theta_dot (rad/s) | std r_ddot (rad/s^2) | xi at bound | kappa at bound |",
        "| --- | --- | --- | --- | --- |",
    ]
    for variant, row in feedback_rows:
        lines.append(
            f"| {label(variant)} | {_pm(row['theta_dot_variability'])} | "
            f"{_pm(row['r_ddot_variability'])} | {_pct(row['xi_at_bound'])} | "
            f"{_pct(row['kappa_at_bound'])} |"
        )
    return [*lines, ""]


def _reward_term_lines(summary: dict[str, Any]) -> list[str]:
    """The section "The return split into its reward terms" (paper eq. 4), per variant."""
    names = _reward_terms()
    lines = [
        "## The return split into its reward terms",
        "",
        "Paper eq. 4: r1 pays upward hip speed, r2..r5 penalise tracking error, joint speed, "
        "torque and foot slip. Each is the sum over an episode, the mean of the last training "
        "episodes (exploration noise on, the last 10 logged values of the 100-episode means), "
        f"{SPREAD}; *r1 share* is r1 over the sum of the terms' magnitudes.",
        "",
        "| variant | training return | " + " | ".join(names) + " | r1 share |",
        "| --- | --- | " + " | ".join("---" for _ in names) + " | --- |",
    ]
    for variant, row in summary["variants"].items():
        terms = [row[f"term_{name}"][0] for name in names]
        magnitude = sum(abs(t) for t in terms if np.isfinite(t))
        share = terms[0] / magnitude if magnitude > 0 and np.isfinite(terms[0]) else float("nan")
        lines.append(
            f"| {label(variant)} | {_pm(row['training_return'])} | "
            + " | ".join(_pm(row[f"term_{name}"]) for name in names)
            + f" | {'-' if not np.isfinite(share) else f'{100 * share:.0f}%'} |"
        )
    return lines


def _stage_lines(summary: dict[str, Any]) -> list[str]:
    """The section "Stages of training": the evaluations at 1/60, 1/3 and 1 of the budget."""
    lines = [
        "## Stages of training",
        "",
        "Deterministic evaluation at the checkpoints nearest to 1/60, 1/3 and 1 of the budget "
        f"(the paper: 1M, 20M, 60M of 60M steps); {SPREAD}.",
        "",
        "| variant | stage | steps | eval return | hop height (m) |",
        "| --- | --- | --- | --- | --- |",
    ]
    for variant, row in summary["variants"].items():
        for k, stage in enumerate(row["stages"]):
            name = STAGE_LABELS[k] if k < len(STAGE_LABELS) else f"{stage['fraction']:.3g}"
            steps = f"{stage['steps']:,}" if stage["steps"] is not None else "-"
            lines.append(
                f"| {label(variant)} | {name} | {steps} | {_pm(stage['eval_return'])} | "
                f"{_pm(stage['hop_height'])} |"
            )
    return lines


def _claim_lines(summary: dict[str, Any], total_steps: int) -> list[str]:
    """The section "The paper's claims": each verdict with its evidence."""
    lines = [
        "## The paper's claims",
        "",
        f"Verdicts computed from the numbers above, at a budget of {total_steps:,} steps per "
        "run (the paper: 20M steps, 60M for the progressive hopping).",
        "",
        "| claim | verdict | evidence |",
        "| --- | --- | --- |",
    ]
    for claim in summary["claims"]:
        detail = claim["detail"].replace("|", "\\|")  # a | would end the table cell
        lines.append(f"| {claim['claim']} | **{claim['verdict']}** | {detail} |")
    return lines


def _figure_lines(figures: list[Path], out: Path) -> list[str]:
    """The section "Figures": each of the paper's with its caption (or why it was not drawn),
    then the single panels."""
    lines = ["", "## Figures", ""]
    by_name = {p.stem: p for p in figures if p.suffix == ".png"}
    captions = {
        "ep_reward": "fig:ep_reward - episode reward against steps (mean, min-max band)",
        "cpg_output": "fig:cpg_output - desired positions, Cho et al. vs CPG-Actor",
        "cpg_theta_dot": "fig:cpg_theta_dot - theta_dot over an episode",
        "cpg_r_dot_dot": "fig:cpg_r_dot_dot - r_ddot over an episode",
        "parameters_under_training": "fig:parameters_under_training - CPG vector V, feedback "
        "output-layer weights and biases over training (dark to light)",
        "des_pos": "fig:des_pos - desired positions, MLP actor vs CPG-Actor",
        "des_vel": "fig:des_vel - desired velocities with the +-15 rad/s limits",
        "cpg_actor_training_over_time": "fig:cpg_actor_training_over_time - hip / foot height "
        "and desired HFE / KFE positions at the stages of training",
    }
    for stem, caption in captions.items():
        if stem in by_name:
            rel = by_name[stem].relative_to(out)
            lines += [f"### {caption}", "", f"![{stem}]({rel.as_posix()})", ""]
        else:
            lines += [f"### {caption}", "", "*not drawn (see notes)*", ""]
    lines += [
        "Single panels are also saved: "
        + ", ".join(f"`{p.name}`" for p in figures if p.suffix == ".png" and p.stem not in captions)
        + " (and a PDF of every figure).",
        "",
    ]
    return lines


def _definition_lines() -> list[str]:
    """The section "Definitions": what each column and claim threshold means."""
    return [
        "## Definitions",
        "",
        "* desired position: the joint position command the env tracked (the agent's command "
        "clipped to the joint limits; Cho et al.: the nominal pose + the CPG's x, clipped);",
        "* desired velocity (every agent alike): its finite difference over the control "
        "period, `(p[t] - p[t-1]) / dt`; the first step of an episode is left out (its "
        "previous command is the env's reset pose, not the agent's);",
        "* (command) smoothness: mean over steps, joints and eval episodes of the squared "
        "second difference of the desired position, `(p[t+1] - 2 p[t] + p[t-1])^2`, in rad^2 "
        "(per control step of 0.01 s); lower is smoother, a bang-bang signal scores high; "
        "*joint smoothness* (section Physical metrics) the same of the measured joints;",
        "* velocity share: share of desired joint velocities with `|v| <= 15 rad/s`; p99: "
        "the 99th percentile of `|v|`; both over the steps, joints and eval episodes of a seed;",
        "* time at a joint stop: share of control steps at which a desired position sent lies "
        f"within {signals.JOINT_STOP_TOLERANCE:g} rad of its joint's limit (the action space's "
        "bound);",
        "* hop height: per eval episode, the maximum hip height minus the standing hip height;",
        f"* bootstrap CI: seeds resampled with replacement, {st.RESAMPLES:,} resamples from a "
        f"generator seeded with {st.BOOTSTRAP_SEED} (the same numbers every time), 2.5 and 97.5 "
        "percentiles; each variant resampled on its own, except the hop height at two times "
        "(one draw of seeds for both: the same runs);",
        f"* fewer than {st.MIN_SEEDS} seeds with data on a side: no interval and no verdict "
        "(*not tested in this run*);",
        f"* verdicts: the CIs are shown, the verdicts rest on tests: {st.WELCH} (two-sided) "
        f"between variants (independent runs), a {st.PAIRED} for the hop height at two times "
        f"(the same runs), {st.BAND} for the velocity band; the p-values of every test behind "
        f"the claims are one family, {st.HOLM}-corrected to a family-wise error rate of "
        f"{st.ALPHA:g}; a claim is supported if each of its tests has a {st.HOLM} p < "
        f"{st.ALPHA:g}, a difference in the claimed direction of at least the minimum effect "
        f"({st.MINIMUM_EFFECT['return']} for returns, {st.MINIMUM_EFFECT['hop_height']} for hop "
        "heights) and the claim's other conditions hold;",
        "* claim thresholds: reward ratio of means within [3, 12] with the CPG-Actor's return "
        "higher; open-loop beats Cho et al. if its mean final return is higher than each Cho "
        "variant's run; smooth vs bang-bang if the MLP's mean smoothness is more than 10 times "
        "the CPG-Actor's (the test: mean MLP - 10 x mean CPG-Actor > 0); near the limits if the "
        "mean over seeds of the per-seed 99th percentile of |desired velocity| lies in [9, 18] "
        "rad/s; hop height doubles if the ratio of mean hop heights at the end / at 1M steps "
        "is >= 1.5 and the hop height rose (paired); best during training if the mean return "
        "over the run is higher than every variant's of the same reward; Cho et al. flat if, "
        "for theta_dot and r_ddot and every Cho variant, the CPG-Actor's mean standard "
        "deviation over an episode (after 50 steps) is more than 3 times Cho's.",
        "",
    ]


REPORT_FOLDER = "robustness"  # a reproduction's suite, OUT/robustness/, goes into its report


def robustness_lines(out: Path) -> list[str]:
    """The reproduction report's robustness section, from ``OUT/robustness/robustness.json``
    (``cpg-actor robustness OUT --out OUT/robustness``); none without it."""
    path = Path(out) / REPORT_FOLDER / JSON_FILE
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return []
    return ["## Robustness", "",
            f"Per perturbation, the return retained under it (mean over its levels, per seed; "
            f"`{REPORT_FOLDER}/{MARKDOWN_FILE}` has every level), {data['episodes']} episodes "
            "per level.", "", *verdict_rule(data), *verdict_lines(data), ""]  # fmt: skip
