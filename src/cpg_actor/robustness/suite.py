"""One run under its robot's perturbations: the final policy evaluated deterministically
(:func:`cpg_actor.training.evaluation.evaluate_policy`, the same episodes and env seed for
every level) nominally and at each level of each perturbation.

Per level: the mean return and its fraction of the nominal one (*retention*), the robot's
metrics (``PerturbationTable.metrics``: the hopper's hop height, a quadruped's speed error and
falls), the physical metrics (:mod:`cpg_actor.metrics.physical`: the hopper's hop apex,
which a push does not raise as it does the episode's highest hip, and its fraction of the
nominal one, *apex kept*; joint smoothness, torque rate, power, foot slip, time at a joint
stop), the 99th percentile of |desired velocity| and, for a push, each episode's recovery
time (:mod:`cpg_actor.robustness.recovery`): control steps until the gait cycle is back within
10 % of the same episode's without the push, "not recovered" where it never is (or the robot
fell), "no gait" where the nominal episode has none to come back to.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from cpg_actor.robustness.recovery import nominal_cycle, recovery_steps
from cpg_actor.robustness.runs import CHECKPOINT, RunRef

NOT_RECOVERED = "not recovered"
NO_GAIT = "no gait"


def level_row(traces: dict[str, np.ndarray], metrics: tuple[str, ...],
              nominal_return: float | None = None) -> dict[str, Any]:  # fmt: skip
    """What the suite keeps of one evaluation: mean return (and retention against
    ``nominal_return``), the metrics' means, the physical metrics the traces define (means
    over episodes), the p99 |desired velocity|, the mean length."""
    from cpg_actor.metrics.physical import run_metrics
    from cpg_actor.metrics.signals import velocity_p99
    from cpg_actor.training.evaluation import finite_mean

    mean_return = float(np.mean(traces["episode_return"]))
    row: dict[str, Any] = {"return": mean_return,
                           "returns": [float(r) for r in traces["episode_return"]]}  # fmt: skip
    if nominal_return is not None:
        row["retention"] = mean_return / nominal_return if nominal_return > 0 else math.nan
    for name in metrics:
        if name in traces:
            row[name] = finite_mean(traces[name])
    row.update({name: value for name, value in run_metrics(traces).items()
                if math.isfinite(value)})  # fmt: skip
    row["p99_desired_velocity"] = velocity_p99(traces["desired_velocity"])
    row["length"] = float(np.mean(traces["length"]))
    return row


def recoveries(traces: dict[str, np.ndarray], nominal: dict[str, np.ndarray],
               table) -> list[float | str]:  # fmt: skip
    """Each episode's recovery from its push: control steps, :data:`NOT_RECOVERED` or
    :data:`NO_GAIT`."""
    out: list[float | str] = []
    for env in range(len(traces["episode_return"])):
        pushed = np.flatnonzero(np.nan_to_num(traces["push"][:, env]) > 0.5)
        if pushed.size == 0:  # the episode ended before its push
            out.append(NOT_RECOVERED)
            continue
        push = int(pushed[0])
        reference = nominal_cycle(*table.cycles(nominal, env), after=push)
        if not math.isfinite(reference):
            out.append(NO_GAIT)
            continue
        if traces["length"][env] < nominal["length"][env]:  # it fell (or blew up)
            out.append(NOT_RECOVERED)
            continue
        steps = recovery_steps(*table.cycles(traces, env), push, reference, table.cycle_floor)
        out.append(NOT_RECOVERED if steps is None else float(steps))
    return out


def evaluate_run(run: RunRef, names: list[str], episodes: int, seed: int,
                 progress: Callable[[str], None] = print) -> dict[str, Any]:  # fmt: skip
    """The suite on ``run``'s final policy: the perturbations ``names`` of its robot's table,
    ``episodes`` episodes per level from env seed ``seed``."""
    from cpg_actor.config import TrainConfig
    from cpg_actor.deploy import load_policy
    from cpg_actor.robots.common.perturbation import Perturbation
    from cpg_actor.robots.registry import get_robot
    from cpg_actor.training.evaluation import evaluate_policy, nominal_env

    config = TrainConfig.load(run.path / "config.yaml")
    robot = get_robot(config.robot)
    table = robot.perturbations
    sim = robot.simulator(config.env)
    if sim == "mjx":  # perturbations run on the CPU simulators
        config.env = config.env.replace(**robot.simulator_config("mujoco"))
        progress(f"  {run.path}: trained on MJX, evaluated on MuJoCo")
    base = nominal_env(config.env).replace(perturbation=Perturbation())  # the nominal robot
    policy = load_policy(run.path / CHECKPOINT, env_config=base, run_config=config)

    def measure(perturbation: Perturbation) -> dict[str, np.ndarray]:
        config.env = base.replace(perturbation=perturbation)
        return evaluate_policy(policy, config, episodes, seed=seed)

    start = time.perf_counter()
    nominal = measure(Perturbation())
    row = level_row(nominal, table.metrics)
    result: dict[str, Any] = {
        "variant": run.variant, "seed": run.seed, "path": str(run.path), "agent": config.agent,
        "robot": robot.name, "simulator": robot.simulator(config.env), "episodes": episodes,
        "env_seed": seed, "nominal": row, "perturbations": {},
    }  # fmt: skip
    progress(f"  nominal: return {row['return']:.1f} ({time.perf_counter() - start:.1f} s)")
    for name in names:
        axis = table.axes[name]
        levels = []
        for level in axis.levels:
            start = time.perf_counter()
            traces = measure(axis.perturbation(level))
            entry = {"level": level, **level_row(traces, table.metrics, row["return"])}
            if row.get("hop_apex", 0.0) > 0 and "hop_apex" in entry:  # the apex kept
                entry["apex_retention"] = entry["hop_apex"] / row["hop_apex"]
            if axis.field == "push":
                entry["recovery"] = recoveries(traces, nominal, table)
            levels.append(entry)
            unit = f" {axis.unit}" if axis.unit else ""
            progress(f"  {name} {level:g}{unit}: return {entry['return']:.1f} "
                     f"({100 * entry['retention']:.0f}% of nominal; "
                     f"{time.perf_counter() - start:.1f} s)")  # fmt: skip
        result["perturbations"][name] = {
            "field": axis.field, "unit": axis.unit, "description": axis.description,
            "nominal": axis.nominal, "levels": levels,
        }  # fmt: skip
    return result
