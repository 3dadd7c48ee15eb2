"""Cross-simulator transfer: every final policy of a reproduction evaluated in both simulators.

A policy trained in MuJoCo (or PyBullet) is evaluated deterministically, with the same env
seed, in its own simulator and in the other one; per variant the report gives how much of its
return and headline metric (``Robot.headline_metric``: the hopper's hop height) it keeps
(other / own, mean over seeds, paired bootstrap CI). It needs a robot that runs in both.
``cpg-actor transfer OUT`` writes ``OUT/transfer.json``; ``cpg-actor figures`` renders it.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from cpg_actor.api import all_metrics
from cpg_actor.api import statistics as st

TRANSFER_FILE = "transfer.json"
SIMULATORS = ("mujoco", "pybullet")


def evaluate_run(run_dir: Path, episodes: int, seed: int) -> dict[str, dict[str, float]]:
    """``{sim: {"return": mean, METRIC: mean}}`` of a run's last checkpoint, METRIC its
    robot's headline metric."""
    from cpg_actor.api import TrainConfig, evaluate_policy, get_robot, load_policy, nominal_env

    config = TrainConfig.load(run_dir / "config.yaml")
    config.env = nominal_env(config.env)
    robot = get_robot(config.robot)
    if not set(SIMULATORS) <= set(robot.simulators):
        raise ValueError(
            f"transfer evaluates in {' and '.join(SIMULATORS)}: the {robot.name} runs on "
            f"{', '.join(robot.simulators)} ({run_dir})"
        )
    metric = robot.headline_metric
    out: dict[str, Any] = {"trained_in": robot.simulator(config.env)}
    for sim in SIMULATORS:
        config.env = config.env.replace(**robot.simulator_config(sim))
        policy = load_policy(run_dir / "checkpoints" / "last.pt", env_config=config.env)
        traces = evaluate_policy(policy, config, episodes, seed=seed)
        out[sim] = {
            "return": float(np.mean(traces["episode_return"])),
            metric: float(np.nanmean(traces[metric])),
        }
    return out


def write_transfer(
    out: Path, episodes: int = 5, seed: int = 1000, progress=print, add: bool = False
) -> Path:
    """Evaluate every run of ``out`` that has a last checkpoint; write ``TRANSFER_FILE``. In a
    ``cpg-actor reproduce`` directory only its finished runs: another's last checkpoint is
    not a final policy (it may be training now).

    ``add``: keep the runs ``TRANSFER_FILE`` already holds (it must have been made with the
    same ``episodes`` and ``seed``) and evaluate only the others, so that a reproduction
    trained across sittings, whose earlier runs kept their logs but not their checkpoints,
    is evaluated run by run as it finishes."""
    from cpg_actor.api import atomic_write_text, run_robot
    from cpg_actor_studies.reproduction.plan import SETTINGS_FILE
    from cpg_actor_studies.reproduction.results import Results

    results = Results.load(Path(out))
    reproduction = (Path(out) / SETTINGS_FILE).is_file()
    runs: dict[str, dict[str, Any]] = {}
    metric = "hop_height"  # the runs' robot's headline metric (the hopper's without runs)
    if add:
        earlier = load_transfer(out) or {"episodes": episodes, "seed": seed, "runs": {}}
        if (earlier.get("episodes"), earlier.get("seed")) != (episodes, seed):
            raise ValueError(
                f"{Path(out) / TRANSFER_FILE} was made with --episodes {earlier.get('episodes')}"
                f" --seed {earlier.get('seed')}; --add needs the same"
            )
        runs = {variant: dict(seeds) for variant, seeds in earlier["runs"].items()}
        metric = earlier.get("metric", metric)
    for variant, variant_runs in results.runs.items():
        for run in variant_runs:
            if str(run.seed) in runs.get(variant, {}):
                continue
            if not (run.path / "checkpoints" / "last.pt").is_file():
                continue
            if reproduction and not run.finished:
                progress(f"transfer: {variant}/seed{run.seed} skipped (not finished)")
                continue
            progress(f"transfer: {variant}/seed{run.seed}")
            metric = run_robot(run.config).headline_metric
            runs.setdefault(variant, {})[str(run.seed)] = evaluate_run(run.path, episodes, seed)
    data = {"episodes": episodes, "seed": seed, "metric": metric, "runs": runs}
    path = Path(out) / TRANSFER_FILE
    atomic_write_text(json.dumps(data, indent=1) + "\n", path)
    return path


def load_transfer(out: Path) -> dict[str, Any] | None:
    path = Path(out) / TRANSFER_FILE
    try:
        return json.loads(path.read_text()) if path.is_file() else None
    except (json.JSONDecodeError, OSError):
        return None


def kept(data: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Per variant: the share of return and of the headline metric (``data["metric"]``)
    kept in the other simulator."""
    table = {}
    metric = data.get("metric", "hop_height")
    for variant, seeds in data["runs"].items():
        own: dict[str, list[float]] = {"return": [], metric: []}
        other: dict[str, list[float]] = {"return": [], metric: []}
        trained = set()
        for values in seeds.values():
            sim = values["trained_in"]
            trained.add(sim)
            target = next(s for s in SIMULATORS if s != sim)
            for key in own:
                own[key].append(values[sim][key])
                other[key].append(values[target][key])
        table[variant] = {
            "trained_in": ", ".join(sorted(trained)),
            "seeds": len(seeds),
            **{f"{key}_own": st.mean_std(own[key]) for key in own},
            **{f"{key}_other": st.mean_std(other[key]) for key in other},
            **{f"{key}_kept": _kept(other[key], own[key]) for key in own},
        }
    return table


def _kept(other: list[float], own: list[float]) -> st.Interval | None:
    """other / own, ratio of means over the seeds, with a paired bootstrap CI; with fewer
    than ``MIN_SEEDS`` seeds the ratio alone (its ``low`` and ``high`` NaN: no interval)."""
    a, b = np.asarray(other, dtype=float), np.asarray(own, dtype=float)
    keep = np.isfinite(a) & np.isfinite(b)
    if keep.sum() >= st.MIN_SEEDS:
        return st.bootstrap_ratio(a, b, paired=True)
    if not keep.any() or b[keep].mean() <= 0:
        return None
    return st.Interval(float(a[keep].mean() / b[keep].mean()), float("nan"), float("nan"))


def transfer_lines(data: dict[str, Any] | None) -> list[str]:
    if data is None:
        return []

    def kept_text(interval) -> str:
        if interval is None:
            return "undefined (own value not positive)"
        if not np.isfinite(interval.low):  # too few seeds for an interval
            return f"{100 * interval.estimate:.0f}%"
        return (
            f"{100 * interval.estimate:.0f}% [{100 * interval.low:.0f}, {100 * interval.high:.0f}]"
        )

    metric = data.get("metric", "hop_height")
    info = all_metrics().get(metric)
    name = (info.short or info.label) if info else metric
    unit = f" ({info.unit})" if info and info.unit else ""
    lines = [
        "## Cross-simulator transfer",
        "",
        f"Each final policy evaluated deterministically ({data['episodes']} episodes, env seed "
        f"{data['seed']}) in the simulator it trained in and in the other one (`cpg-actor "
        "transfer`); *kept*: other / own, mean over seeds with a paired bootstrap 95% CI "
        f"(no CI with fewer than {st.MIN_SEEDS} seeds).",
        "",
        "| variant | trained in | seeds | return own | return other | return kept | "
        f"{name} own{unit} | {name} other{unit} | {name} kept |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for variant, row in kept(data).items():
        lines.append(
            f"| `{variant}` | {row['trained_in']} | {row['seeds']} | "
            f"{row['return_own'][0]:.0f} | {row['return_other'][0]:.0f} | "
            f"{kept_text(row['return_kept'])} | {row[f'{metric}_own'][0]:.3f} | "
            f"{row[f'{metric}_other'][0]:.3f} | {kept_text(row[f'{metric}_kept'])} |"
        )
    return lines + [""]
