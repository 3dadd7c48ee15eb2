"""Whether a quadruped trained on cheaper physics learns the same walk: tracking, gait and
transfer after training under each physics setting, next to what the training cost.

    python benchmarks/quadruped_physics_training.py [--robot go1 anymal] [--seeds 100 101 102]
        [--total-steps 300k] [--settings default 4x5 5x4] [--commands 0.3 0.5 0.8]
        [--episodes 8] [--work-dir DIR] [--output benchmarks/results/quadruped_physics_training.md]

The second half of the physics-settings decision (``quadruped_physics_settings.py`` measures
what a setting saves and whether the open-loop trot holds). Per robot, setting and seed:

* train ``cpg-actor`` as ``cpg-actor train --robot ROBOT --seed SEED`` composes it (the robot's
  recipe), with the setting's ``--set`` values, for ``--total-steps`` steps, each run a fresh
  process (``torch.compile`` included in its wall time, as a user's run);
* evaluate it with ``cpg-actor eval`` (deterministic, ``--episodes`` envs, 20 s episodes, env
  seed 1000) at each forward command of ``--commands`` held for the episode, on the physics it
  was trained on ("own") and on the default physics ("default": the transfer back to the
  reference model; for the default setting the two are the same run and measured once);
* report per setting the median over the seeds of: training wall time and steps/s, the mean
  speed error (m/s, mean |forward speed - command|), falls, forward speed, foot slip (m/s, the
  speed of planted feet), over the commands.

``--work-dir`` keeps the runs and evaluations (a temporary folder by default): a run there
with its last checkpoint is not trained again, an evaluation there not run again, so a cut
measurement continues.

Settings (:data:`SETTINGS`): ``default`` (2 ms x 10 substeps, ANYmal B's) and ``4x5`` (4 ms x
5 substeps: the same 20 ms control step), the one change the trot kept
(``benchmarks/results/quadruped_physics_settings.md``), and ``5x4`` (legged_gym's 5 ms x 4,
whose substeps divide the latencies of the robustness suite and of the field's randomisation,
0.5 and 1.5 control steps). The seeds are tuning seeds
(``docs/results/SEEDS.md``): this chooses a setting, it reports no result. It changes no
default.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bench_report import measured, write
from cpg_actor.machine import cpu_model, load_average, usable_cores

ROOT = Path(__file__).resolve().parent.parent
ROBOTS = ("go1", "anymal")
# name -> the train and eval --set values of the setting (each named in full: an evaluation
# on "default" must not take a run's own physics)
SETTINGS = {
    "default": ["env.physics_dt=0.002", "env.decimation=10"],
    "4x5": ["env.physics_dt=0.004", "env.decimation=5"],
    "5x4": ["env.physics_dt=0.005", "env.decimation=4"],  # legged_gym's sim step
}
METRICS = ("speed_error", "fell", "forward_speed", "foot_slip")


def steps_value(text: str) -> int:
    """``300k``, ``2M`` or a plain number of steps."""
    scale = {"k": 1_000, "M": 1_000_000}.get(text[-1:], 1)
    return int(float(text[:-1] if scale > 1 else text) * scale)


def cli(*arguments: str) -> list[str]:
    return [sys.executable, "-m", "cpg_actor.cli", *arguments]


def run(command: list[str]) -> float:
    """Run ``command`` with this tree's package first on the path; its wall time (s)."""
    path = os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])
    start = time.perf_counter()
    done = subprocess.run(command, env=dict(os.environ, PYTHONPATH=path),
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)  # fmt: skip
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed:\n{done.stdout[-3000:]}")
    return time.perf_counter() - start


def sets(values: list[str]) -> list[str]:
    return [item for value in values for item in ("--set", value)]


def train(robot: str, setting: str, seed: int, total_steps: int, run_dir: Path,
          extra: list[str]) -> float:  # fmt: skip
    """Train one run (unless ``run_dir`` holds its last checkpoint); its training wall time (s,
    from its metrics: collection and update)."""
    if (run_dir / "checkpoints" / "last.pt").is_file():
        return training_wall(run_dir)
    values = sets(SETTINGS[setting] + extra)
    run(cli("train", "--robot", robot, "--seed", str(seed), "--total-steps", str(total_steps),
            "--run-dir", str(run_dir), "--no-progress", *values))  # fmt: skip
    return training_wall(run_dir)


def training_wall(run_dir: Path) -> float:
    """The run's training wall time (s): its last logged ``time/train_wall``."""
    import json

    wall = float("nan")
    for line in (run_dir / "metrics.jsonl").read_text().splitlines():
        row = json.loads(line)
        wall = row.get("time/train_wall", wall)
    return float(wall)


def evaluate(run_dir: Path, physics: str, command: float, episodes: int, output: Path,
             extra: list[str]) -> dict[str, float]:  # fmt: skip
    """``cpg-actor eval`` of the run at ``command`` m/s on ``physics``: the mean of each metric
    over the episodes (NaN-aware; a metric no episode defines is NaN)."""
    values = [*SETTINGS[physics], f"env.command_range=[{command},{command}]", *extra]
    if not output.is_file():  # else done before (--work-dir)
        run(cli("eval", str(run_dir), "--episodes", str(episodes), "--output", str(output),
                "--overwrite", *sets(values)))  # fmt: skip
    with np.load(output, allow_pickle=False) as traces:
        return {name: nanmean(traces[name]) for name in METRICS if name in traces}


def nanmean(values) -> float:
    values = np.asarray(values, dtype=float)
    return float(np.nanmean(values)) if np.isfinite(values).any() else float("nan")


def median(values: list[float]) -> float:
    values = [v for v in values if np.isfinite(v)]
    return statistics.median(values) if values else float("nan")


def one(robot: str, setting: str, seed: int, args, work: Path) -> dict:
    """One run: its training and its evaluations, ``{"wall", "sps", (physics, command):
    metrics}``."""
    run_dir = work / f"{robot}-{setting}-seed{seed}"
    wall = train(robot, setting, seed, args.total_steps, run_dir, args.set)
    result: dict = {"wall": wall, "sps": args.total_steps / wall if wall > 0 else float("nan")}
    for physics in dict.fromkeys([setting, "default"]):
        for command in args.commands:
            output = work / f"{run_dir.name}-{physics}-{command}.npz"
            result[physics, command] = evaluate(run_dir, physics, command, args.episodes,
                                                output, args.eval_set)  # fmt: skip
            print(f"{robot} {setting} seed {seed} on {physics} at {command} m/s: "
                  + ", ".join(f"{k} {v:.3f}" for k, v in result[physics, command].items()),
                  file=sys.stderr, flush=True)  # fmt: skip
    return result


def number(value: float, digits: int = 3) -> str:
    return f"{value:.{digits}f}" if np.isfinite(value) else "-"


def table(robot: str, runs: dict[str, list[dict]], commands: list[float]) -> list[str]:
    """A row per (setting, physics evaluated on): medians over the seeds of the means over the
    commands, and the speed error per command."""
    head = ["setting", "evaluated on", "seeds", "training s", "steps/s", "speed error, m/s",
            *(f"error at {c}" for c in commands), "falls", "forward speed, m/s",
            "foot slip, m/s"]  # fmt: skip
    lines = [f"### {robot}", "", "| " + " | ".join(head) + " |",
             "| " + " | ".join(["---"] * 2 + ["---:"] * (len(head) - 2)) + " |"]  # fmt: skip
    for setting, results in runs.items():
        for physics in dict.fromkeys([setting, "default"]):
            own = "own" if physics == setting else "default (transfer)"

            def over(name: str, chosen=commands, physics=physics, results=results) -> float:
                return median([statistics.fmean(r[physics, c][name] for c in chosen)
                               for r in results])  # fmt: skip

            lines.append("| " + " | ".join([
                setting, own, str(len(results)),
                number(median([r["wall"] for r in results]), 0),
                number(median([r["sps"] for r in results]), 0),
                number(over("speed_error")),
                *(number(over("speed_error", [c])) for c in commands),
                number(over("fell"), 2), number(over("forward_speed")),
                number(over("foot_slip")),
            ]) + " |")  # fmt: skip
    return lines + [""]


def report(args, provenance: str, sections: list[str]) -> list[str]:
    return [
        "# Quadruped physics settings: what training on them learns",
        "",
        f"{provenance}, on {cpu_model()}, {usable_cores()} usable cores (load "
        f"{load_average()} at the end).",
        "",
        f"`cpg-actor` trained {args.total_steps:,} steps per run with the robot's recipe on "
        f"tuning seeds {', '.join(map(str, args.seeds))}; evaluated deterministically on "
        f"{args.episodes} episodes per command ({', '.join(map(str, args.commands))} m/s, each "
        "held for the episode) on the physics it trained on and on the default physics. "
        "Medians over the seeds of the means over the commands (module docstring).",
        "",
        *sections,
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robot", nargs="+", choices=ROBOTS, default=list(ROBOTS))
    parser.add_argument("--settings", nargs="+", choices=list(SETTINGS),
                        default=["default", "4x5"])  # fmt: skip
    parser.add_argument("--seeds", nargs="+", type=int, default=[100, 101, 102])
    parser.add_argument("--total-steps", type=steps_value, default=300_000)
    parser.add_argument("--commands", nargs="+", type=float, default=[0.3, 0.5, 0.8])
    parser.add_argument("--episodes", type=int, default=8, help="envs per evaluation")
    parser.add_argument("--set", action="append", default=[],
                        help="extra training --set value (tests: tiny runs)")  # fmt: skip
    parser.add_argument("--eval-set", action="append", default=[],
                        help="extra evaluation --set value (tests: short episodes)")  # fmt: skip
    parser.add_argument("--work-dir", default=None,
                        help="runs and evaluations kept here, reused (default: a temporary "
                        "folder)")  # fmt: skip
    parser.add_argument("--output", default="benchmarks/results/quadruped_physics_training.md")
    args = parser.parse_args(argv)
    if args.total_steps <= 0 or args.episodes <= 0:
        parser.error("--total-steps and --episodes must be positive")
    command = "python benchmarks/quadruped_physics_training.py " + " ".join(
        sys.argv[1:] if argv is None else argv)  # fmt: skip
    provenance = measured(command)
    sections: list[str] = []
    with contextlib.ExitStack() as stack:
        work = args.work_dir or stack.enter_context(
            tempfile.TemporaryDirectory(prefix="physics-training-"))  # fmt: skip
        Path(work).mkdir(parents=True, exist_ok=True)
        for robot in args.robot:  # the file rewritten after each robot: a cut run keeps them
            runs = {setting: [one(robot, setting, seed, args, Path(work)) for seed in args.seeds]
                    for setting in args.settings}  # fmt: skip
            sections += table(robot, runs, args.commands)
            write(args.output, report(args, provenance, sections))
    return 0


if __name__ == "__main__":
    sys.exit(main())
