"""Hopper environment throughput (control steps per second) next to the raw simulator ceiling.

For each backend and number of environments N the script measures, in the same run:

* ``env``: ``HopperVectorEnv(N).step`` with hopping actions (each env follows a 2 Hz
  squat-and-extend sinusoid with its own phase), everything included: actuator law every
  physics substep, observation, reward, autoreset. One env step = ``decimation`` substeps.
* MuJoCo ceilings, the same model with its actuators disabled and the same robot states, no
  environment:
  ``mj_step loop``: a bare Python loop of ``mujoco.mj_step`` over N ``MjData`` split across
  the same number of threads (``concurrent.futures``; mj_step releases the GIL), and
  ``rollout``: ``mujoco.rollout`` doing ``decimation`` steps per robot in C++, the faster of
  MuJoCo's own thread pool (``Rollout(nthread=threads)``) and the env's
  :class:`~cpg_actor.envs.backends.threaded_rollout.ThreadedRollout` (the calling thread and
  helpers), both timed. Both hold the torques constant, so they do strictly less work than
  the env.
* PyBullet ceiling: ``stepSimulation`` in a bare loop on the same worlds of N robots.

Throughput is env steps (robot x control step) per second; a ceiling's is its substeps per
second divided by ``decimation``. Each figure is the best of ``--repeats`` timed blocks
(the machine may be shared); env and ceilings are measured interleaved.

Run: ``python benchmarks/env_throughput.py`` (writes ``benchmarks/results/env_throughput.md``);
``--quick`` for a short check (prints only, N <= 64), ``--max-n`` to cap N.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from cpg_actor.envs import HopperConfig, HopperVectorEnv
from cpg_actor.machine import cpu_model, load_average, usable_cores

DEFAULT_OUT = Path(__file__).resolve().parent / "results" / "env_throughput.md"
SIZES = (1, 16, 64, 256, 1024)
ENV_STEPS_BUDGET = {"mujoco": 20_000, "pybullet": 4_000}  # robot-steps per timed block


def machine_description() -> list[str]:
    import gymnasium
    import mujoco

    from cpg_actor.envs.backends.pybullet_backend import pybullet

    load = load_average()
    return [
        f"- CPU: {cpu_model()}, {usable_cores()} usable logical core(s) "
        f"(os.cpu_count() = {os.cpu_count()})",
        f"- Python {platform.python_version()} on {platform.system()} {platform.release()}; "
        f"numpy {np.__version__}, mujoco {mujoco.__version__}, "
        f"pybullet API {pybullet.getAPIVersion()}, gymnasium {gymnasium.__version__}",
        f"- load average when the run started (1, 5, 15 min): {load}",
    ]


def hopping_actions(num_envs: int, steps: int, control_dt: float) -> np.ndarray:
    """(steps, N, 2): 2 Hz squat-and-extend around the nominal pose, a phase per env."""
    t = np.arange(steps)[:, None] * control_dt
    phase = np.linspace(0.0, 2.0 * np.pi, num_envs, endpoint=False)[None, :]
    angle = 2.0 * np.pi * 2.0 * t + phase
    return np.stack([0.4 + 0.3 * np.sin(angle), -0.8 - 0.6 * np.sin(angle)], axis=-1)


def best_rate(fn, work: int, repeats: int) -> float:
    """Best (highest) work / second over ``repeats`` calls of ``fn``."""
    best = 0.0
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = max(best, work / (time.perf_counter() - start))
    return best


def bench_size(sim: str, num_envs: int, repeats: int, budget: int) -> dict:
    config = HopperConfig(sim=sim)
    env = HopperVectorEnv(num_envs, config)
    steps = max(5, min(2000, budget // num_envs))
    actions = hopping_actions(num_envs, 50 + steps, config.control_dt)
    env.reset(seed=0)
    for t in range(50):  # get the robots hopping before timing
        env.step(actions[t])

    def run_env() -> None:
        for t in range(steps):
            env.step(actions[50 + t])

    backend = env.sim.backend
    row = {"sim": sim, "N": num_envs, "threads": env.num_threads, "steps": steps}
    decimation = config.decimation
    if sim == "mujoco":
        import mujoco
        from mujoco import rollout

        from cpg_actor.envs.actuator import Actuator
        from cpg_actor.envs.backends.mujoco_backend import STATE_SPEC, load_model
        from cpg_actor.envs.backends.threaded_rollout import ThreadedRollout

        # the project's MJCF with its actuators switched off: constant joint torques instead
        model = load_model(config.physics_dt, config.foot_friction)
        model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_ACTUATION.value
        torque_spec = mujoco.mjtState.mjSTATE_QFRC_APPLIED.value
        states = backend._state.copy()
        torque = Actuator.from_config(config)(env.sim.desired, backend.joint_pos, backend.joint_vel)
        datas = []
        for i in range(num_envs):
            data = mujoco.MjData(model)
            mujoco.mj_setState(model, data, states[i], STATE_SPEC)
            data.qfrc_applied[1:3] = torque[i]
            datas.append(data)
        threads = env.num_threads
        chunks = [datas[i::threads] for i in range(threads)]
        pool = ThreadPoolExecutor(threads) if threads > 1 else None

        loop_steps = max(1, steps // 4)  # the bare loop is timed on a quarter of the steps

        def loop(chunk) -> None:
            for _ in range(loop_steps * decimation):
                for data in chunk:
                    mujoco.mj_step(model, data)

        def run_loop() -> None:
            if pool is None:
                loop(datas)
            else:
                list(pool.map(loop, chunks))

        roller = rollout.Rollout(nthread=threads if threads > 1 else 0)
        roll_datas = [mujoco.MjData(model) for _ in range(max(1, threads))]
        control = np.zeros((num_envs, decimation, model.nv))
        control[:, :, 1:3] = torque[:, None, :]
        out = np.empty((num_envs, decimation, states.shape[1]))

        def run_rollout() -> None:
            for _ in range(steps):
                roller.rollout(
                    [model] * num_envs, roll_datas, states, control, control_spec=torque_spec,
                    skip_checks=True, nstep=decimation, initial_warmstart=None, state=out,
                    sensordata=None, chunk_size=max(1, num_envs // (4 * threads)),
                )  # fmt: skip

        # the env's own way of stepping: the calling thread and helper threads
        threaded = ThreadedRollout(model, num_envs, threads)

        def run_threaded() -> None:
            for _ in range(steps):
                threaded.rollout(states, control, out, None, torque_spec, decimation)

        env_rate = loop_rate = roll_rate = 0.0
        for _ in range(repeats):  # interleaved: a busy neighbour affects them all alike
            env_rate = max(env_rate, best_rate(run_env, steps * num_envs, 1))
            loop_rate = max(loop_rate, best_rate(run_loop, loop_steps * num_envs, 1))
            roll_rate = max(roll_rate, best_rate(run_rollout, steps * num_envs, 1))
            roll_rate = max(roll_rate, best_rate(run_threaded, steps * num_envs, 1))
        if pool is not None:
            pool.shutdown()
        roller.close()
        threaded.close()
        row.update(env=env_rate, loop=loop_rate, rollout=roll_rate)
    else:
        clients = [world.client for world in backend._worlds]

        def run_bare() -> None:
            for _ in range(steps * decimation):
                for client in clients:
                    client.stepSimulation()

        env_rate = bare_rate = 0.0
        for _ in range(repeats):
            env_rate = max(env_rate, best_rate(run_env, steps * num_envs, 1))
            bare_rate = max(bare_rate, best_rate(run_bare, steps * num_envs, 1))
        row.update(env=env_rate, loop=bare_rate, rollout=None)
    env.close()
    return row


def fmt_rate(value: float | None) -> str:
    return "-" if value is None else f"{value:,.0f}"


def fmt_ratio(num: float, den: float | None) -> str:
    return "-" if not den else f"{100.0 * num / den:.0f}%"


def table(rows: list[dict]) -> list[str]:
    lines = [
        "| backend | N | threads | env steps/s | ceiling: bare step loop | env / loop "
        "| ceiling: mujoco.rollout | env / rollout |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['sim']} | {r['N']} | {r['threads']} | {fmt_rate(r['env'])} | "
            f"{fmt_rate(r['loop'])} | {fmt_ratio(r['env'], r['loop'])} | "
            f"{fmt_rate(r['rollout'])} | {fmt_ratio(r['env'], r['rollout'])} |"
        )
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="short run, N <= 64, print only")
    parser.add_argument("--max-n", type=int, default=None, help="largest N to run")
    parser.add_argument("--sims", default="mujoco,pybullet", help="comma-separated backends")
    parser.add_argument("--repeats", type=int, default=None, help="timed blocks per figure (3)")
    parser.add_argument("--out", type=Path, default=None, help=f"markdown file ({DEFAULT_OUT})")
    args = parser.parse_args(argv)
    max_n = args.max_n if args.max_n is not None else (64 if args.quick else max(SIZES))
    repeats = args.repeats if args.repeats is not None else (1 if args.quick else 3)
    scale = 0.25 if args.quick else 1.0
    out = args.out if args.out is not None else (None if args.quick else DEFAULT_OUT)
    sims = [s.strip() for s in args.sims.split(",") if s.strip()]
    for sim in sims:
        if sim not in ENV_STEPS_BUDGET:
            parser.error(f"unknown backend {sim!r}; use mujoco and/or pybullet")
    if max_n < 1 or repeats < 1:
        parser.error("--max-n and --repeats must be >= 1")

    machine = machine_description()
    command = "python benchmarks/env_throughput.py " + " ".join(argv or sys.argv[1:])
    print("\n".join(machine), flush=True)
    rows = []
    for sim in sims:
        for n in [n for n in SIZES if n <= max_n]:
            row = bench_size(sim, n, repeats, int(ENV_STEPS_BUDGET[sim] * scale))
            rows.append(row)
            print(table([row])[-1], flush=True)
    lines = table(rows)
    config = HopperConfig()
    report = [
        "# Environment throughput",
        "",
        f"`{command.strip()}`, {datetime.date.today().isoformat()}: control steps per second "
        f"of the hopper (physics {1 / config.physics_dt:.0f} Hz, decimation {config.decimation}, "
        f"control {1 / config.control_dt:.0f} Hz), best of {repeats} timed block(s) each.",
        "",
        *machine,
        "",
        *lines,
        "",
        "*env*: `HopperVectorEnv(N).step` with hopping actions, all included (actuator law every "
        "substep, observation, reward, autoreset). *bare step loop*: MuJoCo: a Python loop of "
        "`mujoco.mj_step` over N `MjData` on the same number of threads (`concurrent.futures`); "
        "PyBullet: `stepSimulation` on the same worlds of N robots (16 per world). "
        "*mujoco.rollout*: the same substeps looped in C++ by `mujoco.rollout`, the faster of "
        "MuJoCo's thread pool and the env's `ThreadedRollout` (calling thread and helpers). "
        "Ceilings start from the env's robot states, switch the model's actuators off and "
        "hold the joint torques constant (no actuator law, no observation).",
        "",
        "*threads*: the env's MuJoCo stepping threads (`HopperVectorEnv` default: the usable "
        "cores, at least 8 robots per thread); the bare loop and rollout use as many. When "
        "the load average above is close to the core count, other processes held cores during "
        "the run and multi-threaded figures show little or no thread scaling.",
        "",
    ]
    print("\n".join(lines))
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = out.with_suffix(out.suffix + ".tmp")
        tmp.write_text("\n".join(report))
        tmp.replace(out)
        print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
