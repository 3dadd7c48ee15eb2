"""Quadruped PPO training on the CPU next to its physics ceiling, paired per iteration in one
run, and where an iteration's time goes.

    python benchmarks/quadruped_train_throughput.py [--robot go1 anymal] [--iterations 6]
        [--agent cpg-actor] [--num-envs N] [--no-compile] [--set KEY=VALUE ...]
        [--output benchmarks/results/quadruped_train_throughput.md]

Per robot, its run as ``cpg-actor train --robot ROBOT`` composes it (the robot's recipe,
``throughput``, and the agent's tuned settings on it; ``eval_interval=0``): one warm-up
iteration (and the compile), then ``--iterations`` timed ones, each a whole iteration
(``Runner.collect`` + ``Runner.update``). Before each, the ceiling: ``mujoco.rollout`` of the
env's own model (the same MJCF, actuators, timestep and substeps) stepping the same robots on the
same threads through as many control steps as an iteration has, from the env's current states
with the last desired joint positions held, nothing else: the faster of MuJoCo's own thread pool
(``rollout.Rollout(nthread=n)``) and the env's ``ThreadedRollout`` (the calling thread and
helpers), each the best of two. The share is each iteration's steps per second over the ceiling
measured right before it (a machine whose speed drifts slows both alike), the median over the
iterations. The replayed motion: the env's own physics calls of the iteration (their start
states and controls, recorded) replayed back to back on the env's threads right after it, the
same motion without anything between the calls: what the training's walking, falling robots cost
the physics, against the held pose of the ceiling; "the env's physics over its replay" is the time
of the env's physics calls over the replay's (above 1: the calls are slowed by what runs between
them).

Breakdown (``time.perf_counter`` around the parts, summed over the timed iterations, per
control step of one robot): physics (the env's ``mujoco.rollout`` calls), the task's step in
numpy (the rest of the env's ``step``: actions, readings, reward, observation, autoreset),
the torch face (numpy to tensors and back, ``TorchVectorEnv``), the policy and CPG (the
policy's ``act``), the rest of the collection (values of cut episodes, reward scaling, storage,
episode log, GAE) and the update (``Runner.update``, per sample).
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import statistics
import sys
import time

from cpg_actor.machine import brief_openmp_spinning, cpu_model, load_average, usable_cores

brief_openmp_spinning(os.environ)  # as the cpg-actor command runs (before torch loads)

import numpy as np  # noqa: E402
import torch  # noqa: E402

from bench_report import measured, write  # noqa: E402
from cpg_actor.config import compose_config, parse_override  # noqa: E402
from cpg_actor.robots.common.mujoco_runtime import CONTROL_SPEC, mujoco  # noqa: E402
from cpg_actor.robots.common.threaded_rollout import ThreadedRollout  # noqa: E402
from cpg_actor.training.runner import Runner  # noqa: E402

ROBOTS = ("go1", "anymal")
PARTS = ("physics", "task", "torch_face", "policy", "collect_other", "update")


class Timer:
    """Seconds spent in wrapped callables, by part."""

    def __init__(self) -> None:
        self.seconds = dict.fromkeys(PARTS, 0.0)
        self.seconds["env_step"] = 0.0
        self.seconds["torch_step"] = 0.0

    def wrap(self, part: str, function):
        @functools.wraps(function)
        def timed(*args, **kwargs):
            start = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                self.seconds[part] += time.perf_counter() - start

        return timed

    def snapshot(self) -> dict[str, float]:
        return dict(self.seconds)


class Ceiling:
    """``mujoco.rollout`` of the env's robots on its threads, nothing else (module doc)."""

    def __init__(self, env, steps: int) -> None:
        self.env, self.steps = env, steps
        model, n, threads = env.model, env.num_envs, env.num_threads
        self.decimation = env.config.decimation
        self.pool = mujoco.rollout.Rollout(nthread=threads if threads > 1 else 0)
        self.datas = [mujoco.MjData(model) for _ in range(threads)]
        self.threaded = ThreadedRollout(model, n, threads)
        self.chunk = max(1, -(-n // (4 * threads)))
        nstate = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS.value)
        self.state = np.zeros((n, nstate))
        self.out = np.zeros((n, self.decimation, nstate))
        self.control = np.zeros((n, self.decimation, model.nu))

    def _start(self) -> None:
        env = self.env
        np.copyto(self.state, env.get_state()[env.quadruped.state_key]["physics"].numpy())
        self.control[:] = env.episode.last_action[:, None, :]

    def _pool_step(self) -> None:
        model = self.env.model
        self.pool.rollout(
            [model] * self.env.num_envs, self.datas, self.state, self.control,
            control_spec=CONTROL_SPEC, skip_checks=True, nstep=self.decimation,
            initial_warmstart=None, state=self.out, chunk_size=self.chunk,
        )  # fmt: skip
        np.copyto(self.state, self.out[:, -1])

    def _threaded_step(self) -> None:
        self.threaded.rollout(self.state, self.control, self.out, None, CONTROL_SPEC,
                              self.decimation)  # fmt: skip
        np.copyto(self.state, self.out[:, -1])

    def rates(self, repeats: int = 2) -> dict[str, float]:
        """Control steps per second (summed over the robots) of MuJoCo's pool and of
        ``ThreadedRollout``, each the best of ``repeats`` runs of an iteration's steps."""
        result = {}
        for name, step in (("pool", self._pool_step), ("threaded", self._threaded_step)):
            best = 0.0
            for _ in range(repeats):
                self._start()
                begin = time.perf_counter()
                for _ in range(self.steps):
                    step()
                best = max(best, self.steps * self.env.num_envs / (time.perf_counter() - begin))
            result[name] = best
        return result

    def replay(self, calls: list[tuple], repeats: int = 2) -> float:
        """Control steps per second of the env's own physics calls of an iteration
        (``calls``: their start states and controls, as :class:`Recorder` kept them) replayed
        back to back on a ``ThreadedRollout`` of the env's threads, the sensors read as the env
        reads them: the same motion as the training's, nothing between the calls; the best
        of ``repeats``."""
        env = self.env
        next_state = np.zeros_like(env._next)
        sensors = np.zeros_like(env._sensors)
        best = 0.0
        for _ in range(repeats):
            begin = time.perf_counter()
            for state, control, spec, nstep in calls:
                self.threaded.rollout(state, control, next_state, sensors, spec, nstep)
            seconds = time.perf_counter() - begin
            best = max(best, len(calls) * env.num_envs / seconds)
        return best

    def close(self) -> None:
        self.pool.close()
        self.threaded.close()


class Recorder:
    """Keeps the start states and controls of the env's physics calls (:meth:`Ceiling.replay`)."""

    def __init__(self, stepper) -> None:
        self.calls: list[tuple] = []
        self.on = False
        rollout = stepper.rollout

        def recorded(state, control, next_state, sensordata, spec, nstep):
            if self.on:
                self.calls.append((state.copy(), control.copy(), spec, nstep))
            return rollout(state, control, next_state, sensordata, spec, nstep)

        stepper.rollout = recorded


def instrument(runner: Runner, timer: Timer) -> Recorder:
    """Timers around the parts of the run's iteration (module doc)."""
    env = runner.env.unwrapped
    env.stepper.rollout = timer.wrap("physics", env.stepper.rollout)
    recorder = Recorder(env.stepper)  # outside the physics' timer (its copies are not physics)
    env.step = timer.wrap("env_step", env.step)
    runner.env.step = timer.wrap("torch_step", runner.env.step)
    policy = runner.rollout.policy
    policy.act = timer.wrap("policy", policy.act)
    return recorder


def measure(robot: str, args: argparse.Namespace) -> dict:
    values = {"robot": robot, "agent": args.agent, "eval_interval": 0}
    if args.num_envs is not None:
        values["num_envs"] = args.num_envs
    overrides = list(args.set)
    if args.no_compile:
        overrides.append("ppo.compile=false")
    config = compose_config(None, None, values, overrides)
    config.total_steps = (args.iterations + 1) * config.steps_per_iteration
    torch.set_num_threads(config.torch_threads)
    runner = Runner(config, run_dir=None, tensorboard=False)
    env = runner.env.unwrapped
    timer = Timer()
    ceiling = Ceiling(env, config.ppo.num_steps)
    rows = []
    try:
        runner.start_episodes()
        runner.collect()  # warm-up (and the compile)
        runner.update()
        recorder = instrument(runner, timer)
        for _ in range(args.iterations):
            rates = ceiling.rates()
            recorder.calls.clear()
            recorder.on = True
            before = timer.snapshot()
            start = time.perf_counter()
            runner.collect()
            collected = time.perf_counter()
            runner.update()
            end = time.perf_counter()
            recorder.on = False
            after = timer.snapshot()
            replay = ceiling.replay(recorder.calls)
            spent = {name: after[name] - before[name] for name in after}
            sps = config.steps_per_iteration / (end - start)
            rows.append({
                "SPS": sps, "ceiling": max(rates.values()), "pool": rates["pool"],
                "threaded": rates["threaded"], "share": sps / max(rates.values()),
                "share_pool": sps / rates["pool"], "replay": replay, "share_replay": sps / replay,
                "physics_over_replay": replay * spent["physics"] / config.steps_per_iteration,
                "collect": collected - start,
                "update": end - collected, **{f"t_{k}": v for k, v in spent.items()},
            })  # fmt: skip
    finally:
        ceiling.close()
        runner.close()
    result = {key: statistics.median(row[key] for row in rows) for key in rows[0]}
    # the breakdown: sums over the timed iterations, per control step of one robot (us)
    samples = args.iterations * config.steps_per_iteration
    total = {key: sum(row[key] for row in rows) for key in rows[0] if key.startswith("t_")}
    collect = sum(row["collect"] for row in rows)
    update = sum(row["update"] for row in rows)
    parts = {
        "physics": total["t_physics"],
        "task": total["t_env_step"] - total["t_physics"],
        "torch_face": total["t_torch_step"] - total["t_env_step"],
        "policy": total["t_policy"],
        "collect_other": collect - total["t_torch_step"] - total["t_policy"],
        "update": update,
    }
    result["breakdown_us"] = {name: 1e6 * seconds / samples for name, seconds in parts.items()}
    result["iteration_us"] = 1e6 * (collect + update) / samples
    result.update(
        num_envs=config.num_envs, threads=env.num_threads,
        steps_per_iteration=config.steps_per_iteration, compile=config.ppo.compile,
        decimation=env.config.decimation, physics_dt=env.config.physics_dt,
        shares=[row["share"] for row in rows],
    )  # fmt: skip
    return result


def table(results: dict[str, dict]) -> list[str]:
    lines = [
        "| robot | envs | threads | training SPS | ceiling SPS (pool / threaded) | of ceiling, "
        "paired (min-max) | of MuJoCo's pool, paired | replayed motion SPS | of it, paired | "
        "the env's physics over its replay |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for robot, r in results.items():
        lines.append(
            f"| {robot} | {r['num_envs']} | {r['threads']} | {r['SPS']:,.0f} | "
            f"{r['ceiling']:,.0f} ({r['pool']:,.0f} / {r['threaded']:,.0f}) | "
            f"{r['share']:.0%} ({min(r['shares']):.0%}-{max(r['shares']):.0%}) | "
            f"{r['share_pool']:.0%} | {r['replay']:,.0f} | {r['share_replay']:.0%} | "
            f"{r['physics_over_replay']:.2f} |"
        )
    lines += [
        "",
        "Where an iteration's time goes, us per control step of one robot (the update per "
        "sample, the same thing), summed over the timed iterations:",
        "",
        "| robot | physics | task step (numpy) | torch face | policy + CPG | rest of collection "
        "| update | whole iteration |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for robot, r in results.items():
        b = r["breakdown_us"]
        cells = " | ".join(f"{b[p]:.1f} ({b[p] / r['iteration_us']:.0%})" for p in PARTS)
        lines.append(f"| {robot} | {cells} | {r['iteration_us']:.1f} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", nargs="+", choices=ROBOTS, default=list(ROBOTS))
    parser.add_argument("--agent", default="cpg-actor")
    parser.add_argument("--iterations", type=int, default=6, help="timed iterations per robot")
    parser.add_argument("--num-envs", type=int, default=None, help="override the recipe's")
    parser.add_argument("--no-compile", action="store_true", help="ppo.compile=false")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a config override, as cpg-actor train --set")  # fmt: skip
    parser.add_argument("--json", action="store_true", help="print one JSON line, write nothing")
    parser.add_argument("--output", default="benchmarks/results/quadruped_train_throughput.md")
    args = parser.parse_args()
    if args.iterations < 1:
        parser.error(f"--iterations must be >= 1, got {args.iterations}")
    if args.num_envs is not None and args.num_envs < 1:
        parser.error(f"--num-envs must be >= 1, got {args.num_envs}")
    for text in args.set:
        try:
            parse_override(text)
        except ValueError as error:
            parser.error(str(error))
    results = {}
    for robot in args.robot:
        results[robot] = measure(robot, args)
        print(robot, json.dumps(results[robot]), file=sys.stderr, flush=True)
    if args.json:
        print(json.dumps(results))
        return
    command = (
        f"python benchmarks/quadruped_train_throughput.py --robot {' '.join(args.robot)} "
        f"--agent {args.agent} --iterations {args.iterations}"
        + (f" --num-envs {args.num_envs}" if args.num_envs else "")
        + (" --no-compile" if args.no_compile else "")
        + "".join(f" --set {text}" for text in args.set)
    )
    first = next(iter(results.values()))
    lines = [
        "# Quadruped training throughput on the CPU, against the physics ceiling",
        "",
        measured(command) + f", on {cpu_model()}, {usable_cores()} usable cores "
        f"(load {load_average()}), torch {torch.__version__}, mujoco {mujoco.__version__}.",
        "",
        f"Agent `{args.agent}`, each robot's recipe (`throughput`, `ppo.compile="
        f"{str(first['compile']).lower()}`), {first['steps_per_iteration']:,} control steps per "
        f"iteration, a control step = {first['decimation']} substeps of "
        f"{1000 * first['physics_dt']:g} ms. Ceiling: `mujoco.rollout` of the env's own model, "
        "the same robots and threads, as many control steps as an iteration, from the env's "
        "states with the last desired positions held; the faster of MuJoCo's pool and the env's "
        "`ThreadedRollout`, measured right before each timed iteration; shares are the median "
        "over the iterations of each one's SPS over its own ceiling "
        "(`benchmarks/quadruped_train_throughput.py`, module docstring). "
        "Replayed motion: the env's "
        "own physics calls of each iteration replayed back to back right after it (the same "
        "motion as the training's, nothing between the calls).",
        "",
        *table(results),
        "",
    ]
    write(args.output, lines)


if __name__ == "__main__":
    main()
