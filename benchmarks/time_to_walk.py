"""Wall-clock time and env steps from nothing to walking: a quadruped's time to track its
forward-speed command, per agent, next to the physics ceiling measured in the same run.

    python benchmarks/time_to_walk.py [--robot go1] [--agents cpg-actor,mlp-warm,mlp]
        [--seeds 100] [--max-steps 3000000] [--eval-interval 40960]
        [--output benchmarks/results/time_to_walk.md]

The quadruped's analogue of ``benchmarks/time_to_hop.py``. The task is the robot's as
``cpg-actor train --robot ROBOT`` trains it: flat ground, a forward-speed command uniform in
[0, 1] m/s per episode, 20 s episodes (the forward task: the omnidirectional one does not
exist yet). Each agent trains as ``cpg-actor train --robot ROBOT --agent AGENT --seed SEED``
composes it (the robot's recipe, ``throughput``, and the agent's tuned settings on the
quadrupeds), plus :data:`SETTINGS` and any ``--set``, until the target or ``--max-steps``
PPO steps.

One target for all agents (:func:`reached`): the deterministic evaluation
(:mod:`cpg_actor.training.evaluation`: the mean action, one episode on each of
``--eval-episodes`` envs of its own, the same reset seed every time) has a mean speed error
(mean |forward speed - command| over each episode, averaged) of at most
``--max-speed-error`` (0.1 m/s, the quadruped's tracking tolerance in ``docs/quadruped.md``)
and no episode fell. Not 0.15 m/s: the Go1's trot preset, untrained, already tracks within
0.11-0.12 m/s, so at 0.15 the CPG-Actor would walk before its first update and the
benchmark would time nothing but the start. The agent is evaluated before its first update
and every ``--eval-interval`` env steps (rounded to whole iterations) by the trainer's own
evaluation hook; the evaluations run on envs of their own and draw no random numbers, so the
runs train exactly as they would without them.

The start is charged. ``cpg-actor`` starts from the robot's CPG preset, the trot, which no
search produced: nothing to charge. ``mlp-warm`` is first fitted to that same trot by
behaviour cloning (its warm start: ``warm_start.rollout_steps`` control steps of the trot on
each of the ``num_envs`` envs, then the fit); those env steps and that wall time are added to
its own (shown as start + PPO = total; the cap counts PPO steps). An agent that starts from
a searched gait (``agent_config.start_gait``) is refused: its search is not rerun here.

Time is training wall time (collection and update, ``torch.compile`` included, evaluations
excluded) plus the start's. Each run is a fresh process, one at a time. The physics ceiling
is measured in each run's process before and after its training
(:func:`quadruped_throughput.physics_ceiling`: ``mujoco.rollout`` of the run's own model and
substeps, the run's number of robots on the env's threads, nothing else); the report gives
the run's training steps per second against it and how long the physics alone would have
taken for the env steps to the target. Each run also records the share of the machine's CPU
time its hypervisor took meanwhile (:func:`cpg_actor.machine.stolen_share`).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path
from typing import NamedTuple

import numpy as np

from bench_report import (
    charged_warm_start,
    evaluation_recorder,
    json_from_tree,
    measured,
    write,
)
from cpg_actor.training.hooks import Hook

HERE = Path(__file__).resolve().parent
OUTPUT = "benchmarks/results/time_to_walk.md"
AGENTS = ("cpg-actor", "mlp-warm", "mlp")
MAX_SPEED_ERROR = 0.1  # m/s
EVAL_INTERVAL = 40_960  # env steps: 5 iterations of the throughput recipe's 8,192
EVAL_EPISODES = 10
# the benchmark's settings over an agent's tuned ones: mlp-warm, which the quadrupeds have
# no settings for, clones the CPG-Actor's own start (the foot-space trot of the "leg" layout)
# and explores with its action noise (0.1 of the joint ranges), so that the two differ in
# the CPG's structure alone (the config default, 1.0, is the joints' whole half-range)
SETTINGS: dict[str, dict] = {"mlp-warm": {"agent_config": {"cpg_layout": "leg", "init_std": 0.1}}}
# what each evaluation keeps
KEPT = ("eval/speed_error", "eval/fell", "eval/forward_speed", "eval/return")


def reached(evaluation: dict[str, float], max_speed_error: float) -> bool:
    """The evaluation meets the target: a mean speed error of at most ``max_speed_error``
    (m/s) and no episode fell (a NaN of either is no)."""
    error, fell = evaluation["eval/speed_error"], evaluation["eval/fell"]
    return math.isfinite(error) and math.isfinite(fell) and error <= max_speed_error and fell == 0


class RunSpec(NamedTuple):
    """One run: ``agent`` on ``robot`` from ``seed`` until the target or ``max_steps`` PPO
    steps, evaluated every ``eval_interval`` env steps on ``eval_episodes`` episodes;
    ``overrides`` the ``--set`` values; the ceiling timed ``ceiling_seconds`` per method.
    JSON-able as a dict, for a run in a fresh process."""

    robot: str
    agent: str
    seed: int
    max_steps: int
    eval_interval: int
    eval_episodes: int
    max_speed_error: float
    overrides: list[str]
    ceiling_seconds: float


def run_config(spec: RunSpec):
    """The run's :class:`TrainConfig`: as ``cpg-actor train`` composes it for the robot, the
    agent and the seed, with :data:`SETTINGS` and the ``--set`` values; evaluated every
    ``eval_interval`` env steps, rounded to whole iterations (at least one)."""
    from cpg_actor.config import compose_config

    values = {
        "robot": spec.robot, "agent": spec.agent, "seed": spec.seed,
        "total_steps": spec.max_steps, "eval_episodes": spec.eval_episodes,
        **SETTINGS.get(spec.agent, {}),
    }  # fmt: skip
    config = compose_config(None, None, values, spec.overrides)
    config.eval_interval = max(1, round(spec.eval_interval / config.steps_per_iteration))
    config.validate()
    return config


def ceiling(config, robot, seconds: float) -> tuple[float, int]:
    """``(control steps/s, threads)`` of the physics ceiling of the run's envs: the robot's
    env as the run builds it (model, substeps, robots, threads), rolled out alone."""
    from quadruped_throughput import physics_ceiling

    env = robot.make(config.num_envs, config.env, config.env_threads)
    try:
        env.reset(seed=0)
        return physics_ceiling(env, seconds), env.num_threads
    finally:
        env.close()


def project_run(spec: RunSpec) -> dict:
    """One run in this process: the ceiling, the training with every evaluation recorded and
    the start timed, the ceiling again; :func:`summarize`'d."""
    from cpg_actor.robots.registry import get_robot
    from cpg_actor.training.runner import Runner

    config = run_config(spec)
    if config.agent_config.start_gait:
        raise ValueError(
            f"{spec.agent} starts from a searched gait (agent_config.start_gait="
            f"{config.agent_config.start_gait!r}), whose search this benchmark does not rerun "
            "or charge; give agents that start from the CPG preset or nothing"
        )
    robot = get_robot(config.robot)
    before, threads = ceiling(config, robot, spec.ceiling_seconds)

    def met(evaluation: dict[str, float]) -> bool:  # each evaluation, also to the log
        print(f"{spec.agent} seed {spec.seed}: {runner.global_step:,} steps, "
              f"{runner.train_wall:.0f} s, speed error {evaluation['eval/speed_error']:.3f} "
              f"m/s, fell {evaluation['eval/fell']:.0%}", file=sys.stderr, flush=True)  # fmt: skip
        return reached(evaluation, spec.max_speed_error)

    recorder = evaluation_recorder(met)
    stopped = StopOnSignal()
    runner = Runner(config, run_dir=None, tensorboard=False, hooks=[recorder, stopped])
    start = charged_warm_start(runner, config)  # mlp-warm's cloning
    try:
        runner.learn()
        trained_steps, train_wall = runner.global_step, runner.train_wall
    finally:
        runner.close()
    after, _ = ceiling(config, robot, spec.ceiling_seconds)
    history = [{"steps": step, "wall": wall, **{k: e[k] for k in KEPT if k in e}}
               for step, wall, e in recorder.history]  # fmt: skip
    result = summarize(history, spec.max_speed_error, start["steps"], start["wall"])
    result.update(
        sps=trained_steps / train_wall if train_wall > 0 else math.nan,
        ceiling=[before, after], num_envs=config.num_envs, threads=threads,
        trained_steps=trained_steps, train_wall=train_wall, stopped=stopped.asked,
        episode_seconds=config.env.episode_seconds, command_range=list(config.env.command_range),
    )  # fmt: skip
    return result


class StopOnSignal(Hook):
    """A training-loop hook that ends the run after the iteration in which the process got
    SIGTERM (a run cut short to fit a session: its evaluations so far are still reported)."""

    def __init__(self) -> None:
        import signal

        self.asked = False
        signal.signal(signal.SIGTERM, self.ask)

    def ask(self, *_) -> None:
        self.asked = True

    def iteration(self, runner, it) -> None:
        it.stop = it.stop or self.asked


def summarize(history: list[dict], max_speed_error: float, start_steps: int = 0,
              start_wall: float = 0.0) -> dict:  # fmt: skip
    """A run's result from its evaluations (``steps``, ``wall``: PPO env steps and training
    wall time at each, and its ``eval/*``): ``reached``; ``steps`` and ``wall``, the first
    evaluation's that met the target, else the last one's (the run's end); the start's
    ``start_steps`` and ``start_wall``, charged on top; ``first`` (before any update),
    ``best`` (the lowest speed error of those with no fall) and ``lowest`` (the lowest speed
    error, falls or not) evaluations, the first of equals, None for none; ``history``."""
    hit = next((h for h in history if reached(h, max_speed_error)), None)
    end = hit if hit is not None else (history[-1] if history else {"steps": 0, "wall": 0.0})
    finite = [h for h in history if math.isfinite(h["eval/speed_error"])]
    standing = [h for h in finite if h["eval/fell"] == 0]  # no episode fell

    def lowest(entries: list[dict]) -> dict | None:
        return min(entries, key=lambda h: h["eval/speed_error"]) if entries else None

    return {
        "reached": hit is not None,
        "steps": end["steps"],
        "wall": end["wall"],
        "start_steps": start_steps,
        "start_wall": start_wall,
        "first": history[0] if history else None,
        "best": lowest(standing),
        "lowest": lowest(finite),
        "history": history,
    }


def total_steps(run: dict) -> int:
    """Env steps to the run's end point (the target, else its end): its start's and its own."""
    return run["start_steps"] + run["steps"]


def total_wall(run: dict) -> float:
    """Wall time to the run's end point: its start's and its own training's."""
    return run["start_wall"] + run["wall"]


def tree_run(spec: RunSpec) -> dict:
    """:func:`project_run` in a fresh process with this tree's package."""
    arguments = [__file__, "--one-run", json.dumps(spec._asdict())]
    return json_from_tree(HERE.parent / "src", arguments, show_stderr=True)


def one_run(text: str) -> int:
    """``--one-run``: a :func:`project_run` from its JSON spec; prints its result as JSON."""
    print(json.dumps(project_run(RunSpec(**json.loads(text)))))
    return 0


def split(total: float, start: float, show) -> str:
    """``total`` as "start + PPO = total" where a start was charged."""
    if not start:
        return show(total)
    return f"{show(start)} + {show(total - start)} = **{show(total)}**"


def kilo(steps: float) -> str:
    """Env steps, in thousands from 10,000 on."""
    return f"{steps / 1000:,.0f}k" if steps >= 10_000 else f"{steps:,.0f}"


def seconds(wall: float) -> str:
    return f"{wall:,.0f} s"


def evaluation_text(entry: dict | None) -> str:
    if entry is None:
        return "-"
    return (
        f"{entry['eval/speed_error']:.3f} m/s"
        + (f", fell {entry['eval/fell']:.0%}" if entry["eval/fell"] else "")
        + f" (at {kilo(entry['steps'])})"
    )


def overrides(values: dict, prefix: str = "") -> list[str]:
    """A nested mapping of config values as ``KEY=VALUE`` texts (``--set``'s form)."""
    texts = []
    for key, value in values.items():
        if isinstance(value, dict):
            texts += overrides(value, f"{prefix}{key}.")
        else:
            texts.append(f"{prefix}{key}={value}")
    return texts


def run_row(agent: str, seed: int, run: dict, max_steps: int) -> str:
    """The report's row of one run."""
    ceiling_rate = float(np.mean(run["ceiling"]))
    if run["reached"]:
        steps = split(total_steps(run), run["start_steps"], kilo)
        wall = split(total_wall(run), run["start_wall"], seconds)
        physics = seconds(total_steps(run) / ceiling_rate)
    else:
        start = f" (+ start {kilo(run['start_steps'])}, {seconds(run['start_wall'])})"
        cap = run["steps"] if run.get("stopped") else max_steps  # cut short: its last evaluation
        steps = (f"not reached by {kilo(cap)}" + (" (stopped there by hand)" if run.get("stopped")
                 else "") + (start if run["start_steps"] else ""))  # fmt: skip
        wall = f"- (ran {seconds(total_wall(run))})"
        physics = "-"
    stolen = run.get("stolen", math.nan)
    cells = [
        f"`{agent}`", str(seed), steps, wall, physics, evaluation_text(run["first"]),
        evaluation_text(run["best"]), evaluation_text(run["lowest"]), f"{run['sps']:,.0f}",
        " / ".join(f"{c:,.0f}" for c in run["ceiling"]), f"{run['sps'] / ceiling_rate:.0%}",
        f"{stolen:.0%}" if math.isfinite(stolen) else "-",
    ]  # fmt: skip
    return "| " + " | ".join(cells) + " |"


def report(args, runs: list[tuple[str, int, dict]], planned: int, provenance: str) -> list[str]:
    """The Markdown report of the ``runs`` done so far, ``(agent, seed, result)``, of
    ``planned``."""
    task = runs[0][2] if runs else {"episode_seconds": math.nan, "command_range": [math.nan] * 2}
    low, high = task["command_range"]
    settings = "; ".join(
        f"`{agent}`: `" + " ".join(overrides(values)) + "`"
        for agent, values in SETTINGS.items()
        if agent in {a for a, _, _ in runs}
    )
    lines = [
        f"# Time to walk: the {args.robot} from nothing to tracking its forward-speed command",
        "",
        provenance,
        "",
        f"Target, one for all agents: the deterministic evaluation ({args.eval_episodes} "
        f"episodes of {task['episode_seconds']:g} s with the mean action, forward command "
        f"uniform in [{low:g}, {high:g}] m/s per episode, on envs of its own) has a mean "
        f"speed error <= {args.max_speed_error} m/s "
        f"and no episode fell; evaluated before the first update and every "
        f"{args.eval_interval:,} env steps (rounded to whole iterations), to "
        f"{args.max_steps:,} PPO steps at most. Time: training wall time (collection and "
        "update, compilation included, evaluations excluded) plus the start's. `cpg-actor` "
        "starts from the trot preset (no search to charge); `mlp-warm` is first cloned from "
        "that trot, and its env steps and wall time are charged (start + PPO = total). "
        "Each run in a fresh process, one at a time. Each agent trains as `cpg-actor train "
        f"--robot {args.robot} --agent AGENT --seed SEED` composes it"
        + (f", with for {settings}" if settings else "")
        + (
            f"; every run with `{' '.join(f'--set {o}' for o in args.overrides)}`"
            if args.overrides
            else ""
        )
        + ".",
        "",
        "Physics ceiling: `mujoco.rollout` of the run's own model (same substeps, the run's "
        "robots on the env's threads, standing), measured in the run's process before / "
        "after its training. Physics alone: the env steps to the target at the ceiling's "
        "mean rate. Training steps/s: the run's PPO steps over its training wall time, "
        "compilation included (a run that stops after a few iterations is mostly "
        "compilation). CPU stolen: the share of the machine's CPU time its hypervisor gave to "
        "something else during the run.",
        "",
        "| agent | seed | env steps to the target | wall time to the target | physics alone "
        "| before the first update: speed error | best speed error with no fall | lowest speed "
        "error | training steps/s | ceiling steps/s | of ceiling | CPU stolen |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    lines += [run_row(agent, seed, run, args.max_steps) for agent, seed, run in runs]
    if len(runs) < planned:
        lines += ["", f"In progress: {len(runs)} of {planned} runs done."]
    return lines + [""]


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--one-run"]:
        return one_run(argv[1])
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robot", default="go1", help="a quadruped (default go1)")
    parser.add_argument("--agents", default=",".join(AGENTS), help="comma-separated, in order")
    parser.add_argument("--seeds", default="100", help="comma-separated (default 100)")
    parser.add_argument("--max-steps", type=int, default=3_000_000,
                        help="PPO env steps per run at most (default 3000000)")  # fmt: skip
    parser.add_argument("--eval-interval", type=int, default=EVAL_INTERVAL,
                        help="env steps between evaluations (default 40960)")  # fmt: skip
    parser.add_argument("--eval-episodes", type=int, default=EVAL_EPISODES)
    parser.add_argument("--max-speed-error", type=float, default=MAX_SPEED_ERROR,
                        help="the target's speed error, m/s (default 0.1)")  # fmt: skip
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="KEY=VALUE", help="a config value for every run")  # fmt: skip
    parser.add_argument("--ceiling-seconds", type=float, default=3.0,
                        help="timed seconds per ceiling measurement (default 3)")  # fmt: skip
    parser.add_argument("--output", default=OUTPUT)
    args = parser.parse_args(argv)
    agents, seeds = check_args(parser, args)

    from cpg_actor.machine import (
        brief_openmp_spinning,
        cpu_model,
        cpu_times,
        load_average,
        stolen_share,
        usable_cores,
    )

    brief_openmp_spinning(os.environ)  # as the cpg-actor command runs (before torch loads)
    import torch

    from cpg_actor.robots.common.mujoco_runtime import mujoco

    command = (
        f"python benchmarks/time_to_walk.py --robot {args.robot} --agents {','.join(agents)} "
        f"--seeds {','.join(map(str, seeds))} --max-steps {args.max_steps} "
        f"--eval-interval {args.eval_interval} --eval-episodes {args.eval_episodes} "
        f"--max-speed-error {args.max_speed_error}"
        + "".join(f" --set {o}" for o in args.overrides)
        + (f" --output {args.output}" if args.output != OUTPUT else "")
    )
    runs: list[tuple[str, int, dict]] = []
    planned = len(agents) * len(seeds)
    for seed in seeds:
        for agent in agents:
            spec = RunSpec(args.robot, agent, seed, args.max_steps, args.eval_interval,
                           args.eval_episodes, args.max_speed_error, args.overrides,
                           args.ceiling_seconds)  # fmt: skip
            cpu_start = cpu_times()
            run = tree_run(spec)
            run["stolen"] = stolen_share(cpu_start, cpu_times())  # a neighbour's load
            runs.append((agent, seed, run))
            print(f"seed {seed} {agent}: {json.dumps(run)}", flush=True)
            provenance = (
                measured(command) + f", on {cpu_model()}, {usable_cores()} usable cores (load "
                f"{load_average()} at the last run's end), torch {torch.__version__}, mujoco "
                f"{mujoco.__version__}."
            )
            write(args.output, report(args, runs, planned, provenance))  # after every run
    return 0


def check_args(parser: argparse.ArgumentParser, args) -> tuple[list[str], list[int]]:
    """The agents and seeds; one clear line (parser.error) for what is wrong."""
    from cpg_actor.agents import AGENTS as REGISTERED
    from cpg_actor.robots.registry import ROBOTS

    quadrupeds = sorted(name for name, r in ROBOTS.items() if "speed_error" in r.metrics)
    if args.robot not in quadrupeds:
        parser.error(f"--robot {args.robot}: not a quadruped; one of {', '.join(quadrupeds)}")
    agents = [a.strip() for a in args.agents.split(",") if a.strip()]
    ppo = sorted(name for name in REGISTERED if REGISTERED[name].trainer == "ppo")
    unknown = [a for a in agents if a not in ppo]
    if not agents or unknown:
        parser.error(f"--agents {args.agents}: unknown {', '.join(unknown) or 'none given'}; "
                     f"agents trained by PPO: {', '.join(ppo)}")  # fmt: skip
    try:
        seeds = [int(s) for s in args.seeds.split(",")]
    except ValueError:
        seeds = []
    if not seeds or min(seeds) < 0:
        parser.error(f"--seeds {args.seeds}: give integers >= 0, comma-separated, e.g. 100,101")
    for name in ("max_steps", "eval_interval", "eval_episodes"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')} must be a positive integer")
    if not args.max_speed_error > 0 or not args.ceiling_seconds > 0:
        parser.error("--max-speed-error and --ceiling-seconds must be positive numbers")
    return agents, seeds


if __name__ == "__main__":
    raise SystemExit(main())
