"""Wall-clock time and env steps from nothing to walking: a quadruped's time to track its
forward-speed command (or, with ``--grid``, the evaluation protocol's grid of velocity
commands), per agent, next to the physics ceiling measured in the same run.

    python benchmarks/time_to_walk.py [--robot go1] [--agents cpg-actor,mlp-warm,mlp]
        [--seeds 100] [--max-steps 3000000] [--eval-interval 40960]
        [--grid [--grid-episode-seconds 5]] [--output benchmarks/results/time_to_walk.md]

The quadruped's analogue of ``benchmarks/time_to_hop.py``. The task is the robot's as
``cpg-actor train --robot ROBOT`` trains it: flat ground, a forward-speed command uniform in
[0, 1] m/s per episode, 20 s episodes (the forward task). Each agent trains as
``cpg-actor train --robot ROBOT --agent AGENT --seed SEED`` composes it (the robot's recipe,
``throughput``, and the agent's tuned settings on the quadrupeds), plus :data:`SETTINGS` and
any ``--set``, until the target or ``--max-steps`` PPO steps.

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

``--grid``: the omnidirectional task (issue 52's "error <= 0.15 m/s over the grid, flat").
Each agent trains as ``cpg-actor train --robot ROBOT --preset omni --agent AGENT --seed
SEED`` composes it (the field's command ranges, a new command every 5 s, some standing; the
CPG's planar steps), plus :data:`SETTINGS` and any ``--set``; a robot without that task (the
hopper) is refused. Its evaluation, in the same places (before the first update, every
``--eval-interval`` env steps, through the trainer's hook, so the runs still train exactly as
without it: tested), is the evaluation protocol's grid on flat ground
(:class:`cpg_actor.robustness.grid_evaluation.GridEvaluation`: the 12 commands of
:data:`cpg_actor.robustness.protocol.GRID`, each held for ``--eval-episodes`` episodes, 1 by
default, of ``--grid-episode-seconds``, 5 s by default, with the mean action on envs of its
own, the same seed every time; no payload or push checks). Its target
(:func:`reached_grid`): the linear-velocity error (the mean over each episode of the
per-step error, start-up included), averaged over the 12 commands, of at most
``--max-speed-error`` (0.15 m/s by default here) and no episode fell on any command. Its
cost at the defaults: 12 episodes of 250 control steps of one robot per evaluation, against
the forward evaluation's one episode of 1,000 steps on 10 robots (5 s episodes: a quarter of
the protocol's 20 s, so that evaluating every 40,960 steps stays a small share of a run; the
start-up then weighs 4 times as much in the error as on 20 s; the untrained CPG-Actor of the
omni preset, whose planar steps already track much of the grid, lands just above 0.15 m/s on
5 s episodes and below it on 20 s ones, where the benchmark would time nothing but its
start). Excluded from the time like every evaluation; the report gives each run's mean
seconds per evaluation. Its report goes to
``benchmarks/results/time_to_walk_grid.md`` unless ``--output``, and its rows name the task.
Either mode also writes every run's result (its evaluations included) as JSON beside the
report (the same name, ``.json``), rewritten with the report after each run; beside a report
named by ``--output``, an existing file of that name is refused unless ``--overwrite``.

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
from typing import NamedTuple

import numpy as np

from bench_report import companions, measured, write
from cpg_actor.files import atomic_write_text
from cpg_actor.training.hooks import Hook
from time_to_target import (
    answer,
    evaluate_every,
    evaluation_recorder,
    in_fresh_process,
    split,
    to_target,
    total_steps,
    total_wall,
    train,
)

OUTPUT = "benchmarks/results/time_to_walk.md"
AGENTS = ("cpg-actor", "mlp-warm", "mlp")
GRID_OUTPUT = "benchmarks/results/time_to_walk_grid.md"
MAX_SPEED_ERROR = 0.1  # m/s
EVAL_INTERVAL = 40_960  # env steps: 5 iterations of the throughput recipe's 8,192
EVAL_EPISODES = 10
# --grid: the target over the protocol's grid, one episode per command, 5 s each
GRID_MAX_ERROR = 0.15  # m/s
GRID_EPISODES = 1
GRID_EPISODE_SECONDS = 5.0
# each task's error the target is on: the forward speed's, the grid's mean linear velocity's
ERRORS = {"forward": "eval/speed_error", "grid": "eval/lin_vel_error"}
# the benchmark's settings over an agent's tuned ones: mlp-warm, which the quadrupeds have
# no settings for, clones the CPG-Actor's own start (the foot-space trot of the "leg" layout)
# and explores with its action noise (0.1 of the joint ranges), so that the two differ in
# the CPG's structure alone (the config default, 1.0, is the joints' whole half-range)
SETTINGS: dict[str, dict] = {"mlp-warm": {"agent_config": {"cpg_layout": "leg", "init_std": 0.1}}}
# what each evaluation keeps
KEPT = ("eval/speed_error", "eval/fell", "eval/forward_speed", "eval/return",
        "eval/lin_vel_error", "eval/lin_vel_error_max", "eval/yaw_rate_error",
        "eval/fell_commands", "time/eval")  # fmt: skip


def reached(evaluation: dict[str, float], max_speed_error: float,
            error: str = ERRORS["forward"]) -> bool:  # fmt: skip
    """The evaluation meets the target: a mean speed error (its ``error``, the forward
    task's by default) of at most ``max_speed_error`` (m/s) and no episode fell (a NaN of
    either is no)."""
    value, fell = evaluation[error], evaluation["eval/fell"]
    return math.isfinite(value) and math.isfinite(fell) and value <= max_speed_error and fell == 0


def reached_grid(evaluation: dict[str, float], max_error: float) -> bool:
    """``--grid``'s target: the grid evaluation's linear-velocity error, averaged over the
    protocol's commands, of at most ``max_error`` (m/s) and no episode fell on any command
    (``eval/fell``, the share of the grid's episodes that fell, is 0)."""
    return reached(evaluation, max_error, ERRORS["grid"])


class RunSpec(NamedTuple):
    """One run: ``agent`` on ``robot`` from ``seed`` until the target or ``max_steps`` PPO
    steps, evaluated every ``eval_interval`` env steps on ``eval_episodes`` episodes (with
    ``grid``: the omnidirectional task, evaluated on the protocol's grid, ``eval_episodes``
    episodes of ``grid_seconds`` per command); ``overrides`` the ``--set`` values; the
    ceiling timed ``ceiling_seconds`` per method. JSON-able as a dict, for a run in a fresh
    process."""

    robot: str
    agent: str
    seed: int
    max_steps: int
    eval_interval: int
    eval_episodes: int
    max_speed_error: float
    overrides: list[str]
    ceiling_seconds: float
    grid: bool = False
    grid_seconds: float = GRID_EPISODE_SECONDS

    @property
    def mode(self) -> str:
        return "grid" if self.grid else "forward"


def run_config(spec: RunSpec):
    """The run's :class:`TrainConfig`: as ``cpg-actor train`` composes it for the robot, the
    agent and the seed (with ``grid``: and ``--preset omni``), with :data:`SETTINGS` and the
    ``--set`` values; ``agent`` may be a named variant of ``cpg-actor reproduce`` (e.g.
    ``mlp-field``, the field's MLP recipe: its agent with its settings, before ``--set``);
    evaluated every ``eval_interval`` env steps, rounded to whole iterations (at least one)."""
    from cpg_actor.config import compose_config
    from cpg_actor_studies.reproduction.plan import variant_agent, variant_preset

    agent, variant_overrides = variant_agent(spec.agent)
    values = {
        "robot": spec.robot, "agent": agent, "seed": spec.seed,
        "total_steps": spec.max_steps, "eval_episodes": spec.eval_episodes,
        **SETTINGS.get(spec.agent, {}),
    }  # fmt: skip
    overrides = [*variant_overrides, *spec.overrides]
    preset = variant_preset(spec.agent, "omni" if spec.grid else None)
    config = compose_config(preset, None, values, overrides)
    evaluate_every(config, spec.eval_interval)
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

    config = run_config(spec)
    if config.agent_config.start_gait:
        raise ValueError(
            f"{spec.agent} starts from a searched gait (agent_config.start_gait="
            f"{config.agent_config.start_gait!r}), whose search this benchmark does not rerun "
            "or charge; give agents that start from the CPG preset or nothing"
        )
    robot = get_robot(config.robot)
    error = ERRORS[spec.mode]
    grid = None
    if spec.grid:  # the protocol's grid instead of the trainer's episodes (same seed, hook)
        from cpg_actor.robustness.grid_evaluation import GridEvaluation

        grid = GridEvaluation(config, robot, spec.eval_episodes, spec.grid_seconds)
    before, threads = ceiling(config, robot, spec.ceiling_seconds)

    def met(evaluation: dict[str, float]) -> bool:  # each evaluation, also to the log
        steps, wall, _ = recorder.history[-1]  # this evaluation's
        print(f"{spec.agent} seed {spec.seed}: {steps:,} steps, {wall:.0f} s, {spec.mode} "
              f"error {evaluation[error]:.3f} m/s, fell {evaluation['eval/fell']:.0%}",
              file=sys.stderr, flush=True)  # fmt: skip
        return reached(evaluation, spec.max_speed_error, error)

    def evaluated_on_grid(runner) -> None:
        runner.evaluation.evaluator = grid

    recorder = evaluation_recorder(met)
    stopped = StopOnSignal()
    start, runner = train(config, recorder, [stopped], evaluated_on_grid)  # start: mlp-warm's
    trained_steps, train_wall = runner.global_step, runner.train_wall
    after, _ = ceiling(config, robot, spec.ceiling_seconds)
    history = [{"steps": step, "wall": wall, **{k: e[k] for k in KEPT if k in e}}
               for step, wall, e in recorder.history]  # fmt: skip
    result = summarize(history, spec.max_speed_error, start["steps"], start["wall"], error)
    evaluation_seconds = [h["time/eval"] for h in history if "time/eval" in h]
    result.update(
        sps=trained_steps / train_wall if train_wall > 0 else math.nan,
        ceiling=[before, after], num_envs=config.num_envs, threads=threads,
        trained_steps=trained_steps, train_wall=train_wall, stopped=stopped.asked,
        episode_seconds=config.env.episode_seconds, command_range=list(config.env.command_range),
        mode=spec.mode, lateral_range=list(config.env.lateral_range),
        yaw_range=list(config.env.yaw_range),
        command_resample_seconds=config.env.command_resample_seconds,
        eval_episode_seconds=grid.episode_seconds if grid else config.env.episode_seconds,
        eval_seconds=float(np.mean(evaluation_seconds)) if evaluation_seconds else math.nan,
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
              start_wall: float = 0.0, error: str = ERRORS["forward"]) -> dict:  # fmt: skip
    """A run's result from its evaluations (``steps``, ``wall``: PPO env steps and training
    wall time at each, and its ``eval/*``), the target on their ``error`` (the forward
    speed's by default, :data:`ERRORS`): ``reached``; ``steps`` and ``wall``, the first
    evaluation's that met the target, else the last one's (the run's end); the start's
    ``start_steps`` and ``start_wall``, charged on top; ``first`` (before any update),
    ``best`` (the lowest error of those with no fall) and ``lowest`` (the lowest error,
    falls or not) evaluations, the first of equals, None for none; ``history``."""
    finite = [h for h in history if math.isfinite(h[error])]
    standing = [h for h in finite if h["eval/fell"] == 0]  # no episode fell

    def lowest(entries: list[dict]) -> dict | None:
        return min(entries, key=lambda h: h[error]) if entries else None

    return {
        **to_target(history, lambda h: reached(h, max_speed_error, error)),
        "start_steps": start_steps,
        "start_wall": start_wall,
        "first": history[0] if history else None,
        "best": lowest(standing),
        "lowest": lowest(finite),
        "history": history,
    }


def kilo(steps: float) -> str:
    """Env steps, in thousands from 10,000 on."""
    return f"{steps / 1000:,.0f}k" if steps >= 10_000 else f"{steps:,.0f}"


def seconds(wall: float) -> str:
    return f"{wall:,.0f} s"


def evaluation_text(entry: dict | None, error: str = ERRORS["forward"]) -> str:
    if entry is None:
        return "-"
    return (
        f"{entry[error]:.3f} m/s"
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
    """The report's row of one run (its task: ``forward``, or ``grid`` for ``--grid``'s)."""
    ceiling_rate = float(np.mean(run["ceiling"]))
    mode = run.get("mode", "forward")
    error = ERRORS[mode]
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
    each = run.get("eval_seconds", math.nan)
    cells = [
        f"`{agent}`", str(seed), mode, steps, wall, physics, evaluation_text(run["first"], error),
        evaluation_text(run["best"], error), evaluation_text(run["lowest"], error),
        f"{run['sps']:,.0f}", " / ".join(f"{c:,.0f}" for c in run["ceiling"]),
        f"{run['sps'] / ceiling_rate:.0%}", f"{stolen:.0%}" if math.isfinite(stolen) else "-",
        f"{each:.1f} s" if math.isfinite(each) else "-",
    ]  # fmt: skip
    return "| " + " | ".join(cells) + " |"


def report(args, runs: list[tuple[str, int, dict]], planned: int, provenance: str) -> list[str]:
    """The Markdown report of the ``runs`` done so far, ``(agent, seed, result)``, of
    ``planned``."""
    settings = "; ".join(
        f"`{agent}`: `" + " ".join(overrides(values)) + "`"
        for agent, values in SETTINGS.items()
        if agent in {a for a, _, _ in runs}
    )
    title, target = target_text(args, runs[0][2] if runs else None)
    what = "grid lin vel error" if args.grid else "speed error"
    lines = [
        f"# Time to walk: the {args.robot} from nothing to {title}",
        "",
        provenance,
        "",
        f"Target, one for all agents: {target}; evaluated before the first update and every "
        f"{args.eval_interval:,} env steps (rounded to whole iterations), to "
        f"{args.max_steps:,} PPO steps at most. Time: training wall time (collection and "
        "update, compilation included, evaluations excluded) plus the start's. `cpg-actor` "
        "starts from the trot preset (no search to charge); `mlp-warm` is first cloned from "
        "that trot, and its env steps and wall time are charged (start + PPO = total). "
        "Each run in a fresh process, one at a time. Each agent trains as `cpg-actor train "
        f"--robot {args.robot}{' --preset omni' if args.grid else ''} --agent AGENT --seed "
        "SEED` composes it"
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
        "something else during the run. One evaluation: its mean wall time (excluded).",
        "",
        "| agent | seed | task | env steps to the target | wall time to the target "
        f"| physics alone | before the first update: {what} | best {what} with no fall "
        f"| lowest {what} | training steps/s | ceiling steps/s | of ceiling | CPU stolen "
        "| one evaluation |",
        "| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: "
        "| ---: |",
    ]
    lines += [run_row(agent, seed, run, args.max_steps) for agent, seed, run in runs]
    if len(runs) < planned:
        lines += ["", f"In progress: {len(runs)} of {planned} runs done."]
    return lines + [""]


def target_text(args, run: dict | None) -> tuple[str, str]:
    """The report's ``(title, target)`` texts of the task that ran (``run``: a result, None
    before the first)."""
    nan = [math.nan] * 2
    if not args.grid:
        low, high = run["command_range"] if run else nan
        seconds = run["episode_seconds"] if run else math.nan
        return "tracking its forward-speed command", (
            f"the deterministic evaluation ({args.eval_episodes} episodes of {seconds:g} s "
            f"with the mean action, forward command uniform in [{low:g}, {high:g}] m/s per "
            f"episode, on envs of its own) has a mean speed error <= {args.max_speed_error} "
            "m/s and no episode fell"
        )
    from cpg_actor.robustness.protocol import GRID

    fields = (("vx", "command_range", "m/s"), ("vy", "lateral_range", "m/s"),
              ("yaw rate", "yaw_range", "rad/s"))  # fmt: skip
    ranges = ", ".join(f"{name} in [{low:g}, {high:g}] {unit}" for name, key, unit in fields
                       for low, high in [run[key] if run else nan])  # fmt: skip
    resample = run["command_resample_seconds"] if run else math.nan
    return "tracking the evaluation protocol's grid of velocity commands", (
        f"the grid evaluation (the evaluation protocol's {len(GRID)} velocity commands, "
        f"`cpg_actor.robustness.protocol.GRID`, each held for {args.eval_episodes} "
        f"episode(s) of {args.grid_episode_seconds:g} s with the mean action on flat ground, "
        "on envs of its own, reset with the same seed every time; no payload or push checks) "
        f"has a linear-velocity error, averaged over the commands, <= {args.max_speed_error} "
        "m/s and no episode fell on any command. Trained on the omnidirectional task "
        f"(`--preset omni`: {ranges}, a new draw every {resample:g} s, some draws standing)"
    )


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if answer(argv, {"--one-run": (RunSpec, project_run)}):
        return 0
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robot", default="go1", help="a quadruped (default go1)")
    parser.add_argument(
        "--agents",
        default=",".join(AGENTS),
        help="comma-separated, in order; agents or named variants (mlp-field)",
    )
    parser.add_argument("--seeds", default="100", help="comma-separated (default 100)")
    parser.add_argument("--max-steps", type=int, default=3_000_000,
                        help="PPO env steps per run at most (default 3000000)")  # fmt: skip
    parser.add_argument("--eval-interval", type=int, default=EVAL_INTERVAL,
                        help="env steps between evaluations (default 40960)")  # fmt: skip
    parser.add_argument("--eval-episodes", type=int, default=None,
                        help="episodes per evaluation (default 10); with --grid, per "
                        "command (default 1)")  # fmt: skip
    parser.add_argument("--max-speed-error", type=float, default=None,
                        help="the target's speed error, m/s (default 0.1; with --grid, the "
                        "grid's mean linear-velocity error, default 0.15)")  # fmt: skip
    parser.add_argument("--grid", action="store_true",
                        help="the omnidirectional task (--preset omni), evaluated on the "
                        "evaluation protocol's 12 velocity commands, flat")  # fmt: skip
    parser.add_argument("--grid-episode-seconds", type=float, default=None,
                        help="with --grid: each command's episode, s (default 5)")  # fmt: skip
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="KEY=VALUE", help="a config value for every run")  # fmt: skip
    parser.add_argument("--ceiling-seconds", type=float, default=3.0,
                        help="timed seconds per ceiling measurement (default 3)")  # fmt: skip
    parser.add_argument("--output", default=None,
                        help=f"default {OUTPUT} ({GRID_OUTPUT} with --grid); the runs' JSON "
                        "goes beside it (the same name, .json)")  # fmt: skip
    parser.add_argument("--overwrite", action="store_true",
                        help="replace an existing JSON file beside a named --output")  # fmt: skip
    args = parser.parse_args(argv)
    agents, seeds = check_args(parser, args)
    default_output = GRID_OUTPUT if args.grid else OUTPUT
    named = args.output is not None
    args.output = args.output or default_output
    (json_path,) = companions(parser, args.output, (".json",), named, args.overwrite)

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
        + (f" --grid --grid-episode-seconds {args.grid_episode_seconds:g}" if args.grid else "")
        + "".join(f" --set {o}" for o in args.overrides)
        + (f" --output {args.output}" if args.output != default_output else "")
    )
    runs: list[tuple[str, int, dict]] = []
    planned = len(agents) * len(seeds)
    for seed in seeds:
        for agent in agents:
            spec = RunSpec(args.robot, agent, seed, args.max_steps, args.eval_interval,
                           args.eval_episodes, args.max_speed_error, args.overrides,
                           args.ceiling_seconds, args.grid,
                           args.grid_episode_seconds or GRID_EPISODE_SECONDS)  # fmt: skip
            cpu_start = cpu_times()
            run = in_fresh_process(__file__, "--one-run", spec, show_stderr=True)
            run["stolen"] = stolen_share(cpu_start, cpu_times())  # a neighbour's load
            run["machine"] = cpu_model()  # the clock its times were read on
            runs.append((agent, seed, run))
            print(f"seed {seed} {agent}: {json.dumps(run)}", flush=True)
            provenance = (
                measured(command) + f", on {cpu_model()}, {usable_cores()} usable cores (load "
                f"{load_average()} at the last run's end), torch {torch.__version__}, mujoco "
                f"{mujoco.__version__}."
            )
            write(args.output, report(args, runs, planned, provenance))  # after every run
            atomic_write_text(json.dumps([{"agent": a, "seed": s, **r} for a, s, r in runs])
                              + "\n", json_path)  # fmt: skip
    return 0


def check_args(parser: argparse.ArgumentParser, args) -> tuple[list[str], list[int]]:
    """The agents and seeds, each mode's defaults filled in (``eval_episodes``,
    ``max_speed_error``, ``grid_episode_seconds``); one clear line (parser.error) for what is
    wrong."""
    from cpg_actor.agents import AGENTS as REGISTERED
    from cpg_actor.robots.registry import ROBOTS

    if args.grid:
        omni = sorted(
            name for name, r in ROBOTS.items() if hasattr(r.config_class, "OMNI_COMMANDS")
        )
        if args.robot not in omni:
            parser.error(f"--grid --robot {args.robot}: no omnidirectional task (--preset omni) "
                         f"on it; robots with one: {', '.join(omni)}")  # fmt: skip
    elif args.grid_episode_seconds is not None:
        parser.error("--grid-episode-seconds is the grid evaluation's: give it with --grid")
    if args.eval_episodes is None:
        args.eval_episodes = GRID_EPISODES if args.grid else EVAL_EPISODES
    if args.max_speed_error is None:
        args.max_speed_error = GRID_MAX_ERROR if args.grid else MAX_SPEED_ERROR
    quadrupeds = sorted(name for name, r in ROBOTS.items() if "speed_error" in r.metrics)
    if args.robot not in quadrupeds:
        parser.error(f"--robot {args.robot}: not a quadruped; one of {', '.join(quadrupeds)}")
    from cpg_actor_studies.reproduction.plan import VARIANTS, variant_agent

    agents = [a.strip() for a in args.agents.split(",") if a.strip()]
    ppo = sorted(name for name in REGISTERED if REGISTERED[name].trainer == "ppo")
    variants = sorted(name for name in VARIANTS if variant_agent(name)[0] in ppo)
    unknown = [a for a in agents if a not in ppo and a not in variants]
    if not agents or unknown:
        parser.error(f"--agents {args.agents}: unknown {', '.join(unknown) or 'none given'}; "
                     f"agents trained by PPO: {', '.join(ppo)}; or a named variant of one "
                     f"(cpg-actor reproduce's): {', '.join(variants)}")  # fmt: skip
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
    if args.grid:
        if args.grid_episode_seconds is None:
            args.grid_episode_seconds = GRID_EPISODE_SECONDS
        try:  # a whole number of the robot's control steps
            ROBOTS[args.robot].config_class().replace(episode_seconds=args.grid_episode_seconds)
        except ValueError as error:
            parser.error(f"--grid-episode-seconds {args.grid_episode_seconds:g}: {error}")
    for agent in agents:  # --set read and checked as `cpg-actor train --set`, before any run
        spec = RunSpec(args.robot, agent, seeds[0], args.max_steps, args.eval_interval,
                       args.eval_episodes, args.max_speed_error, args.overrides,
                       args.ceiling_seconds, args.grid,
                       args.grid_episode_seconds or GRID_EPISODE_SECONDS)  # fmt: skip
        try:
            run_config(spec)
        except (ValueError, FileNotFoundError) as error:
            parser.error(f"the {agent} runs' config (with --set): {error}")
    return agents, seeds


if __name__ == "__main__":
    raise SystemExit(main())
