"""A reproduction's numbers (``OUT/summary.json``): per variant, per seed, the final return,
the hop height, the desired positions' smoothness and velocity, the physical metrics, the CPG
signals' variability, per stage of training; over seeds their means, medians and bootstrap CIs;
then the paper's claims (:mod:`~cpg_actor_studies.hopper_paper.claims`) and the comparisons
beyond them (:mod:`~cpg_actor_studies.hopper_paper.comparisons`) judged on them."""

from __future__ import annotations

from typing import Any

import numpy as np

from cpg_actor.api import paper_robot, physical, signals
from cpg_actor.api import statistics as st
from cpg_actor_studies.hopper_paper.claims import (
    PAPER_COMPARISON_STEPS,
    PAPER_STAGE_STEPS,
    VELOCITY_LIMIT,
    judge_claims,
)
from cpg_actor_studies.hopper_paper.comparisons import judge_comparisons
from cpg_actor_studies.hopper_paper.figures import steps_at_iteration
from cpg_actor_studies.reproduction import numbers
from cpg_actor_studies.reproduction.results import (
    Results,
    agent_kind,
    sent_positions,
    sent_velocity,
    trace_joint_limits,
)

EARLY_ROWS = 3  # logged evaluations averaged for a hop height "at" a step
# the physical metrics of the final evaluation (the command's smoothness is ``smoothness``)
PHYSICAL_KEYS = tuple(name for name in physical.METRICS if name != "command_smoothness")


def _per_seed(results: Results, variant: str, at_step: float | None) -> dict[str, list[float]]:
    """Per-seed numbers of one variant (NaN where a run lacks the data)."""
    out: dict[str, list[float]] = {
        key: []
        for key in (
            "final_return",
            "eval_return",
            "hop_height",
            "smoothness",
            "velocity_share",
            "velocity_p99",
            "time_at_stop",
            "first_stage_hop_height",
            "hop_height_at_1M",
            "final_hop_height_logged",
            "mean_eval_return",
            "peak_return",
            "peak_step",
            "final_std",
            "training_return",
            "theta_dot_variability",
            "r_ddot_variability",
            "xi_at_bound",
            "kappa_at_bound",
            *PHYSICAL_KEYS,
            *(f"term_{name}" for name in _reward_terms()),
        )
    }
    for run in results.runs.get(variant, []):
        steps, returns = run.return_curve()
        out["final_return"].append(numbers.final_return(steps, returns, at_step=at_step))
        # the deterministic evaluations logged during training (eval_interval)
        hop_steps, hops = run.curve("eval/hop_height")
        out["hop_height_at_1M"].append(
            numbers.final_return(hop_steps, hops, at_step=PAPER_STAGE_STEPS[0], rows=EARLY_ROWS)
        )
        out["final_hop_height_logged"].append(
            numbers.final_return(hop_steps, hops, rows=EARLY_ROWS)
        )
        out["mean_eval_return"].append(numbers.curve_mean(run.curve("eval/return")[1]))
        peak, peak_step = numbers.peak_return(steps, returns)
        out["peak_return"].append(peak)
        out["peak_step"].append(peak_step)
        logged = [row for row in run.metrics if "policy/log_std_0" in row]
        out["final_std"].append(numbers.exploration_std(logged[-1]) if logged else float("nan"))
        # the return of the last training episodes, split into the reward terms r1..r5
        out["training_return"].append(numbers.final_return(*run.curve("charts/episode_return")))
        for name in _reward_terms():
            out[f"term_{name}"].append(numbers.final_return(*run.curve(f"reward_terms/{name}")))
        traces = run.traces()
        first = run.traces(0) if run.stages else None
        nan = float("nan")
        if traces is None:
            for key in (
                "eval_return",
                "hop_height",
                "smoothness",
                "velocity_share",
                "velocity_p99",
                "time_at_stop",
                "theta_dot_variability",
                "r_ddot_variability",
                "xi_at_bound",
                "kappa_at_bound",
                *PHYSICAL_KEYS,
            ):
                out[key].append(nan)
        else:
            # what the robot did (hip, joints, feet): absent (NaN) where traces predate it
            values = physical.run_metrics(traces)
            for key in PHYSICAL_KEYS:
                out[key].append(values[key])
            out["eval_return"].append(float(np.mean(traces["episode_return"])))
            out["hop_height"].append(float(np.mean(traces["hop_height"])))
            # the desired positions the env tracked (T, E, joints), and for every agent alike
            # their finite difference over the control period
            position = sent_positions(traces)
            velocity = sent_velocity(traces)
            limits = trace_joint_limits(traces) if position is not None else None
            if limits is not None and limits[0].size != position.shape[-1]:
                limits = None
            out["smoothness"].append(signals.smoothness(position) if position is not None else nan)
            has_velocity = velocity is not None
            out["velocity_share"].append(
                signals.velocity_share(velocity, VELOCITY_LIMIT) if has_velocity else nan
            )
            out["velocity_p99"].append(signals.velocity_p99(velocity) if has_velocity else nan)
            out["time_at_stop"].append(
                signals.joint_stop_share(position, *limits) if limits is not None else nan
            )
            for name in ("theta_dot", "r_ddot"):
                signal = traces.get(name)
                out[f"{name}_variability"].append(
                    numbers.variability(signal) if signal is not None and signal.ndim == 3 else nan
                )
            # bounded feedback (xi = xi_scale tanh(.)): how often it sits at its bound
            agent_config = run.config.get("agent_config") or {}
            bounded = agent_config.get("feedback_tanh", True)
            for name, scale in (("xi", "xi_scale"), ("kappa", "kappa_scale")):
                values = traces.get(name)
                out[f"{name}_at_bound"].append(
                    numbers.bound_share(values, float(agent_config[scale]))
                    if values is not None
                    and bounded
                    and scale in agent_config
                    and np.any(np.nan_to_num(values) != 0)  # the open loop's feedback is 0
                    else nan
                )
        out["first_stage_hop_height"].append(
            float(np.mean(first["hop_height"])) if first is not None else nan
        )
    return out


def _stages(results: Results, variant: str) -> list[dict[str, Any]]:
    """Per stage of training: steps (of the lowest seed), eval return and hop height over
    seeds."""
    runs = results.runs.get(variant, [])
    count = max((len(run.stages) for run in runs), default=0)
    stages = []
    for k in range(count):
        hops, returns, steps = [], [], None
        for run in runs:
            traces = run.traces(k) if k < len(run.stages) else None
            if traces is None:
                continue
            hops.append(float(np.mean(traces["hop_height"])))
            returns.append(float(np.mean(traces["episode_return"])))
            if steps is None:
                steps = steps_at_iteration(run, run.stages[k]["iteration"])
        fraction = runs[0].stages[k]["fraction"] if k < len(runs[0].stages) else float("nan")
        stages.append(
            {
                "fraction": fraction,
                "steps": steps,
                "seeds": len(hops),
                "hop_height": st.mean_std(hops),
                "eval_return": st.mean_std(returns),
            }
        )
    return stages


REWARD_KEYS = ("c1", "c2", "c3", "c4", "c5", "hop_reward", "apex_weight")
DEFAULT_REWARD = {"c1": 1.0, "c2": -1.0, "c3": -1e-3, "c4": -1e-4, "c5": -0.1,
                  "hop_reward": "hip-velocity", "apex_weight": 200.0}  # fmt: skip


def reward_of(results: Results, variant: str) -> str:
    """The reward a variant trained on, from its first run's saved config (runs saved before
    a key existed: its default); returns are comparable only between equal rewards."""
    runs = results.runs.get(variant) or []
    env = (runs[0].config.get("env") or {}) if runs else {}
    values = {key: env.get(key, DEFAULT_REWARD[key]) for key in REWARD_KEYS}
    if values["hop_reward"] != "apex":
        del values["apex_weight"]
    return ", ".join(f"{k}={v}" for k, v in values.items())


# the per-seed numbers of the per-variant table: each a median over seeds with its bootstrap CI
TABLE_KEYS = ("final_return", "eval_return", "hop_height", "smoothness", "velocity_p99",
              "velocity_share", "time_at_stop", *PHYSICAL_KEYS)  # fmt: skip


def _median_interval(values: list[float]) -> list[float] | None:
    """``[median, low, high]`` over seeds (bootstrap CI), None with fewer than ``MIN_SEEDS``
    seeds with data (no interval for them)."""
    if not st.enough_seeds(values):
        return None
    interval = st.bootstrap(values, "median")
    return [interval.estimate, interval.low, interval.high]


def _reward_terms() -> tuple[str, ...]:
    """Eq. 4's reward terms, the studied robot's (:func:`cpg_actor.robots.registry.paper_robot`)."""
    return paper_robot().paper_parts().reward_terms


def check_hopper_runs(results: Results) -> None:
    """ValueError unless every run is on the robot the paper studies (the hopper): the report
    tests the paper's claims, which are about it (its hop height, its reward terms, its Cho et
    al. baseline)."""
    studied = paper_robot().name
    robots = {run.config.get("robot") or studied for runs in results.runs.values()
              for run in runs}  # fmt: skip
    others = sorted(str(robot) for robot in robots - {studied})
    if others:
        raise ValueError(
            f"the reproduction report is the paper's, on the {studied}; these runs are on "
            f"{', '.join(others)}: use `cpg-actor eval` and `cpg-actor curves` for them"
        )


def summarise(results: Results, total_steps: int) -> dict[str, Any]:
    """Per-variant numbers (means and stds, medians with bootstrap CIs over seeds, the
    per-seed values) and the claim verdicts, of the hopper's runs (:func:`check_hopper_runs`)."""
    check_hopper_runs(results)
    comparison_step = min(total_steps, PAPER_COMPARISON_STEPS)
    variants: dict[str, Any] = {}
    seeds: dict[str, dict[str, list[float]]] = {}
    for variant in results.variants:
        if not results.has(variant):
            continue
        seeds[variant] = _per_seed(results, variant, at_step=None)
        at_comparison = _per_seed(results, variant, at_step=comparison_step)["final_return"]
        seeds[variant]["return_at_comparison"] = at_comparison
        variants[variant] = {
            "kind": agent_kind(variant),
            "reward": reward_of(results, variant),
            "seeds": len(results.runs[variant]),
            "finished": sum(run.finished for run in results.runs[variant]),
            **{key: st.mean_std(values) for key, values in seeds[variant].items()},
            "median": {key: _median_interval(seeds[variant][key]) for key in TABLE_KEYS},
            "per_seed": seeds[variant],
            "stages": _stages(results, variant),
        }
    rewards = {variant: row["reward"] for variant, row in variants.items()}
    return {
        "total_steps": total_steps,
        "comparison_step": comparison_step,
        "variants": variants,
        "claims": judge_claims(seeds, rewards, total_steps),
        "comparisons": judge_comparisons(seeds),
    }
