"""The quadruped env's speed on the CPU next to its raw physics ceiling, measured in one run.

    python benchmarks/quadruped_throughput.py [--envs 16 64 256] [--seconds 5]
        [--output benchmarks/results/quadruped_throughput.md]

* ceiling: ``mujoco.rollout`` of the env's own MJCF (ANYmal B, ``decimation`` substeps of
  ``physics_dt`` per control step, its dcmotor actuators holding the nominal pose), the robots
  split over the same threads as the env, nothing else; the faster of MuJoCo's own thread pool
  and the env's ``ThreadedRollout`` (the calling thread and helpers);
* env: ``AnymalVectorEnv.step`` (the same rollout plus the task in numpy: observation,
  reward terms, falls, autoreset) driven by the open-loop trot of the CPG preset, the CPG
  stepped in torch as a policy would;

control steps per second summed over the robots, after a warm-up.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import torch

from bench_report import measured, write
from cpg_actor.machine import cpu_model, load_average, usable_cores
from cpg_actor.robots.anymal import description as robot
from cpg_actor.robots.anymal.gaits import ANYMAL_GAITS
from cpg_actor.robots.anymal.vector import AnymalVectorEnv
from cpg_actor.robots.common.mujoco_runtime import CONTROL_SPEC, mujoco
from cpg_actor.robots.common.quadruped.gaits import joint_map_for
from cpg_actor.robots.common.threaded_rollout import ThreadedRollout


def physics_ceiling(env, seconds: float) -> float:
    """The physics ceiling of ``env`` (a quadruped's vector env, reset): ``mujoco.rollout`` of
    its own model from its state, ``decimation`` substeps per control step, its actuators
    holding the nominal pose, the robots split over the env's threads, nothing else; control
    steps per second summed over the robots, the faster of MuJoCo's own thread pool and the
    env's ``ThreadedRollout``. The env itself is not stepped."""
    model, threads, num_envs = env.model, env.num_threads, env.num_envs
    (state,) = env.get_state().values()  # {state_key: its arrays}
    start_state = state["physics"].numpy().copy()
    steps = env.config.decimation
    control = np.tile(np.asarray(env.robot.nominal_pose), (num_envs, steps, 1))
    out = np.zeros((num_envs, steps, start_state.shape[1]))
    rollout = mujoco.rollout.Rollout(  # loaded by the backend, after MUJOCO_GL is set
        nthread=threads if threads > 1 else 0
    )
    datas = [mujoco.MjData(model) for _ in range(threads)]
    chunk = max(1, -(-num_envs // (4 * threads)))
    threaded = ThreadedRollout(model, num_envs, threads)

    def physics() -> None:
        rollout.rollout([model] * num_envs, datas, start_state, control,
                        control_spec=CONTROL_SPEC, skip_checks=True, nstep=steps,
                        initial_warmstart=None, state=out, chunk_size=chunk)  # fmt: skip
        np.copyto(start_state, out[:, -1])

    def physics_threaded() -> None:
        threaded.rollout(start_state, control, out, None, CONTROL_SPEC, steps)
        np.copyto(start_state, out[:, -1])

    try:
        return max(rate(physics, num_envs, seconds), rate(physics_threaded, num_envs, seconds))
    finally:
        rollout.close()
        threaded.close()


def rate(step, num_envs: int, seconds: float) -> float:
    """Control steps per second of ``step`` (one control step of ``num_envs`` robots) over
    ``seconds``, after 20 steps of warm-up."""
    for _ in range(20):
        step()
    count, begin = 0, time.perf_counter()
    while time.perf_counter() - begin < seconds:
        step()
        count += 1
    return num_envs * count / (time.perf_counter() - begin)


def rates(num_envs: int, seconds: float) -> dict[str, float]:
    env = AnymalVectorEnv(num_envs)
    env.reset(seed=0)
    cpg = ANYMAL_GAITS.joint_cpg(env.config.control_dt, "trot")
    joint_map = joint_map_for(robot.NOMINAL_POSE)
    state = cpg.initial_state(num_envs)

    def env_step() -> None:
        nonlocal state
        with torch.no_grad():
            output, state = cpg(state)
            env.step(joint_map(output.position).numpy())

    try:
        return {
            "threads": env.num_threads,
            "ceiling": physics_ceiling(env, seconds),
            "env": rate(env_step, num_envs, seconds),
        }
    finally:
        env.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", type=int, nargs="+", default=[16, 64, 256])
    parser.add_argument("--seconds", type=float, default=5.0, help="timed seconds per row")
    parser.add_argument("--output", default="benchmarks/results/quadruped_throughput.md")
    args = parser.parse_args()
    rows = []
    for n in args.envs:
        rows.append((n, rates(n, args.seconds)))
        print(n, rows[-1][1], flush=True)
    command = "python benchmarks/quadruped_throughput.py --envs " + " ".join(map(str, args.envs))
    lines = [
        "# Quadruped (ANYmal B) env throughput on the CPU",
        "",
        measured(command) + f", on {cpu_model()}, {usable_cores()} usable cores "
        f"(load {load_average()}), torch {torch.__version__}, mujoco {mujoco.__version__}.",
        "",
        "Control steps per second (one control step = 10 substeps of 2 ms), summed over robots.",
        "",
        "| robots | threads | ceiling (`mujoco.rollout`) | env with the trot CPG | of ceiling |",
        "| ---: | ---: | ---: | ---: | ---: |",
    ]
    lines += [
        f"| {n} | {r['threads']} | {r['ceiling']:,.0f} | {r['env']:,.0f} | "
        f"{r['env'] / r['ceiling']:.0%} |"
        for n, r in rows
    ]
    write(args.output, lines + [""])


if __name__ == "__main__":
    main()
