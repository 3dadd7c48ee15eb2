"""How well the simulator's threads are used inside training, against the same calls back to back.

    python benchmarks/rollout_threads.py [--agent cpg-actor] [--preset throughput]
        [--num-envs 256] [--iterations 6] [--repeats 3]
        [--output benchmarks/results/rollout_threads.md]

Inside a training rollout the MuJoCo envs (the hopper's backend, the quadruped's vector env)
step their robots with
:class:`~cpg_actor.robots.common.threaded_rollout.ThreadedRollout`: at every control step the
calling thread hands a job to the helper threads and steps chunks of robots itself, then
waits for the helpers. Between two control steps the policy acts on one core and the helpers
sleep. This script trains ``--preset`` (default ``throughput``, compiled; ``anymal``: the
quadruped with that recipe) for ``--iterations`` rollouts
and records, for every ``rollout`` call:

* its wall time;
* how long after the call the first helper woke and began taking chunks (the *start delay*:
  waking a sleeping thread; it is recorded even when the calling thread has taken every chunk
  by then);
* how long the calling thread waited for the helpers after its own last chunk;
* the share of the call's thread time (wall x threads) spent in the threads' chunk loops
  (``mujoco.rollout`` and taking the next chunk).

Then it replays the same calls (the recorded states and controls) back to back on the same
threads, as the physics ceiling is measured (``benchmarks/env_throughput.py``): the helpers
sleep only from one call to the next. The ratio of the two wall times is what interleaving the
policy with the simulation costs the simulation. Last, the two chunk schedules on the same
calls, with the training's median pause between calls (the calling thread busy meanwhile, as with
the policy): the guided one the rollout uses
(:func:`~cpg_actor.robots.common.threaded_rollout.guided_chunks`) and 4 fixed chunks per thread
(the schedule before 28 Nov 2026), alternating, 4 pairs; the median of the paired ratios of
their call times. It also records the share of the machine's CPU time the
hypervisor took (:func:`cpg_actor.machine.stolen_share`) and, on Linux, the guest's idle
driver and its halt-polling window: a virtual CPU that halts when idle is woken through the
host, which is slow when the guest's halt polling is off.

The instrumentation wraps the rollout's methods from this script (the package is not
changed); it adds two clock reads per thread and call.
"""

from __future__ import annotations

import argparse
import statistics
import threading
import time
from pathlib import Path

import numpy as np
import torch

from bench_report import measured, write
from cpg_actor.config import TrainConfig, apply_dict
from cpg_actor.config.presets import preset_values
from cpg_actor.machine import cpu_model, cpu_times, load_average, stolen_share, usable_cores
from cpg_actor.robots.common import threaded_rollout
from cpg_actor.training.runner import Runner

SYSFS = {
    "idle driver": "/sys/devices/system/cpu/cpuidle/current_driver",
    "guest halt polling (ns)": "/sys/module/haltpoll/parameters/guest_halt_poll_ns",
}


def sysfs_facts() -> str:
    """The guest's idle driver and halt-polling window, where Linux exposes them."""
    facts = []
    for name, path in SYSFS.items():
        try:
            facts.append(f"{name} {Path(path).read_text().strip()}")
        except OSError:
            facts.append(f"{name} unknown")
    return ", ".join(facts)


class CallRecorder:
    """Wraps one ``ThreadedRollout`` (its ``rollout``) and the chunk steppers (a class
    attribute, so the helpers' calls too) to time every call; :meth:`stop` undoes it."""

    def __init__(self, rollout: threaded_rollout.ThreadedRollout) -> None:
        self.rollout = rollout
        self.calls: list[dict] = []
        self.inputs: list[tuple] = []
        self._caller = threading.get_ident()
        self._current: dict | None = None
        stepper_call = threaded_rollout.ChunkStepper.__call__
        call = rollout.rollout
        recorder = self

        def timed_stepper(stepper, job):
            start = time.perf_counter()
            stepper_call(stepper, job)
            end = time.perf_counter()
            if recorder._current is not None:
                key = "main" if threading.get_ident() == recorder._caller else "helpers"
                recorder._current[key].append((start, end))

        def timed_call(state, control, next_state, sensordata, control_spec, nstep):
            record = {"main": [], "helpers": []}
            recorder._current = record
            sensors = None if sensordata is None else sensordata.shape
            self.inputs.append((state.copy(), control.copy(), control_spec, nstep, sensors))
            record["start"] = time.perf_counter()
            call(state, control, next_state, sensordata, control_spec, nstep)
            record["end"] = time.perf_counter()
            recorder._current = None
            self.calls.append(record)

        self._restore = stepper_call
        threaded_rollout.ChunkStepper.__call__ = timed_stepper
        rollout.rollout = timed_call

    def stop(self) -> None:
        threaded_rollout.ChunkStepper.__call__ = self._restore
        if "rollout" in vars(self.rollout):  # the instance attribute: the class's method again
            del self.rollout.rollout

    def summary(self) -> dict[str, float]:
        walls, delays, waits, busy = [], [], [], 0.0
        threads = self.rollout.num_threads
        for c in self.calls:
            walls.append(c["end"] - c["start"])
            busy += sum(e - s for s, e in c["main"] + c["helpers"])
            if c["helpers"]:  # the first helper to wake (records are added as each finishes)
                delays.append(min(start for start, _ in c["helpers"]) - c["start"])
            waits.append(c["end"] - c["main"][-1][1])
        return {
            "calls": len(walls),
            "wall_ms": 1e3 * statistics.fmean(walls),
            "delay_mean_us": 1e6 * statistics.fmean(delays) if delays else float("nan"),
            "delay_median_us": 1e6 * statistics.median(delays) if delays else float("nan"),
            "delay_p90_us": 1e6 * float(np.percentile(delays, 90)) if delays else float("nan"),
            "wait_us": 1e6 * statistics.fmean(waits),
            "busy": busy / (threads * sum(walls)),
        }

    def pause_ms(self) -> float:
        """Median time between the end of one call and the start of the next (the policy, the
        env's numpy work, storage: the helpers sleep meanwhile; the median leaves out the
        PPO updates between rollouts)."""
        gaps = [b["start"] - a["end"] for a, b in zip(self.calls, self.calls[1:], strict=False)]
        return 1e3 * statistics.median(gaps) if gaps else 0.0

    def replay_ms(
        self, rollout: threaded_rollout.ThreadedRollout | None = None, pause_ms: float = 0.0
    ) -> float:
        """Mean wall time of the recorded calls replayed on ``rollout`` (default: the recorded
        one), the calling thread busy for ``pause_ms`` between calls (0: back to back)."""
        rollout = rollout or self.rollout
        outputs: dict[tuple, np.ndarray] = {}  # by shape: one array each, as the env keeps
        total = 0.0
        for state, control, spec, nstep, sensor_shape in self.inputs:
            shape = (state.shape[0], nstep, state.shape[1])
            out = outputs.setdefault(shape, np.empty(shape))
            sensors = (
                None
                if sensor_shape is None
                else outputs.setdefault(sensor_shape, np.empty(sensor_shape))
            )
            start = time.perf_counter()
            rollout.rollout(state, control, out, sensors, spec, nstep)
            end = time.perf_counter()
            total += end - start
            while time.perf_counter() < end + pause_ms / 1e3:  # busy, as the policy is
                pass
        return 1e3 * total / len(self.inputs)


def fixed_chunk_rollout(
    rollout: threaded_rollout.ThreadedRollout,
) -> threaded_rollout.ThreadedRollout:
    """A rollout of the same robots and threads with 4 fixed chunks per thread (the schedule
    before the guided one)."""
    size = max(1, -(-rollout.num_robots // (4 * rollout.num_threads)))
    return threaded_rollout.ThreadedRollout(
        rollout.model, rollout.num_robots, rollout.num_threads, size
    )


def env_rollout(env) -> threaded_rollout.ThreadedRollout:
    """The ``ThreadedRollout`` of a MuJoCo env: the hopper's backend's or the quadruped's."""
    for holder in (getattr(getattr(env, "sim", None), "backend", None), env):
        stepper = getattr(holder, "stepper", None)
        if isinstance(stepper, threaded_rollout.ThreadedRollout):
            return stepper
    raise SystemExit(f"{type(env).__name__} does not step with ThreadedRollout")


def measure(agent: str, preset: str, num_envs: int, iterations: int) -> dict[str, float]:
    """Train ``iterations`` rollouts (and updates) after a warm-up one, recording the
    simulator's calls; then replay them."""
    config = TrainConfig(agent=agent)
    apply_dict(config, preset_values(preset), "")
    config.eval_interval, config.num_envs = 0, num_envs
    config.total_steps = (iterations + 1) * config.steps_per_iteration
    runner = Runner(config, run_dir=None, tensorboard=False)
    try:
        stepper = env_rollout(runner.env.unwrapped)
        runner.start_episodes()
        runner.collect()
        runner.update()
        recorder = CallRecorder(stepper)
        before = cpu_times()
        simulation = 0.0
        try:
            for _ in range(iterations):
                simulation += runner.collect()["simulation_time"]
                runner.update()
        finally:
            recorder.stop()
        stolen = stolen_share(before, cpu_times())
        result = recorder.summary()
        result["replay_ms"] = recorder.replay_ms()
        # the schedules compared on the same calls, with training's pauses between them
        result["pause_ms"] = recorder.pause_ms()
        fixed = fixed_chunk_rollout(stepper)
        try:
            pause = result["pause_ms"]
            recorder.replay_ms(fixed, pause)  # its threads' first calls
            ratios = []
            for pair in range(4):  # paired, each schedule first in every other pair
                if pair % 2 == 0:
                    guided_ms = recorder.replay_ms(pause_ms=pause)
                    fixed_ms = recorder.replay_ms(fixed, pause)
                else:
                    fixed_ms = recorder.replay_ms(fixed, pause)
                    guided_ms = recorder.replay_ms(pause_ms=pause)
                ratios.append(fixed_ms / guided_ms)
        finally:
            fixed.close()
        result["fixed_over_guided"] = statistics.median(ratios)
        result["threads"] = stepper.num_threads
        result["stolen"] = stolen
        result["simulation_us"] = 1e6 * simulation / (iterations * config.steps_per_iteration)
        result["num_envs"] = config.num_envs
        return result
    finally:
        runner.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--agent", default="cpg-actor")
    parser.add_argument("--preset", default="throughput", help="throughput or anymal")
    parser.add_argument("--num-envs", type=int, default=256)
    parser.add_argument("--iterations", type=int, default=6)
    parser.add_argument("--repeats", type=int, default=3, help="fresh runs, one after another")
    parser.add_argument("--output", default="benchmarks/results/rollout_threads.md")
    args = parser.parse_args()
    if args.iterations < 1 or args.repeats < 1 or args.num_envs < 1:
        parser.error("--iterations, --repeats and --num-envs must be positive")
    torch.set_num_threads(1)
    rows = []
    for repeat in range(args.repeats):
        row = measure(args.agent, args.preset, args.num_envs, args.iterations)
        rows.append(row)
        print(f"repeat {repeat + 1}: {row}", flush=True)

    command = (
        f"python benchmarks/rollout_threads.py --agent {args.agent} --preset {args.preset} "
        f"--num-envs {args.num_envs} "
        f"--iterations {args.iterations} --repeats {args.repeats}"
    )
    lines = [
        "# The simulator's threads inside training",
        "",
        f"{measured(command)}.",
        "",
        f"Machine: {cpu_model()}, {usable_cores()} usable cores (load {load_average()}), "
        f"{sysfs_facts()}, torch {torch.__version__}. Preset `{args.preset}` (compiled), "
        f"`{args.agent}`, {args.num_envs} envs, {rows[0]['threads']} simulator threads, "
        f"{args.iterations} rollouts of 32 control steps per repeat after a warm-up one.",
        "",
        "| repeat | `env.step`, us per env step | its rollout call, us per env step "
        "| rollout call in training, ms | same calls back to back, ms | training / back to back "
        "| helper start delay, us: mean / median / p90 | calling thread waits, us "
        "| threads stepping robots | pause between calls, ms | fixed chunks / guided "
        "| CPU stolen |",
        "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for i, r in enumerate(rows, 1):
        lines.append(
            f"| {i} | {r['simulation_us']:.1f} | {1e3 * r['wall_ms'] / r['num_envs']:.1f} | "
            f"{r['wall_ms']:.2f} | {r['replay_ms']:.2f} | "
            f"{r['wall_ms'] / r['replay_ms']:.2f}x | {r['delay_mean_us']:,.0f} / "
            f"{r['delay_median_us']:,.0f} / {r['delay_p90_us']:,.0f} | {r['wait_us']:,.0f} | "
            f"{r['busy']:.0%} | {r['pause_ms']:.2f} | {r['fixed_over_guided']:.3f}x | "
            f"{r['stolen']:.0%} |"
        )
    lines += [
        "",
        "`env.step`: the whole step as training times it (the rollout call, observation, "
        "reward, resets, the tensors the trainer gets), per env. "
        "A rollout call steps every robot through one control step (the hopper with its default "
        "actuator law: 10 physics substeps). *Helper start delay*: from the call to the "
        "first helper waking to take chunks; *calling thread waits*: from its own last "
        "chunk to the call's end; *threads stepping robots*: the "
        "share of the call's thread time (wall x threads) in the threads' chunk loops "
        "(`mujoco.rollout` and taking the next chunk); *back "
        "to back*: the recorded calls replayed with nothing between them, as the physics "
        "ceiling is measured; *fixed chunks / guided*: the same calls with 4 fixed chunks "
        "per thread over the guided schedule, with training's median pause between calls "
        "(median of 4 pairs, each schedule first in every other pair, after a warm-up; "
        "above 1: the guided schedule is faster). CPU stolen: the "
        "hypervisor's share of the machine's CPU time during the training.",
    ]
    write(args.output, lines)


if __name__ == "__main__":
    main()
