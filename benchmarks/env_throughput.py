"""Hopper environment throughput (control steps per second) next to the raw simulator ceiling.

For each backend and number of environments N the script measures, in the same run:

* ``env``: ``HopperVectorEnv(N).step`` with hopping actions (each env follows a 2 Hz
  squat-and-extend sinusoid with its own phase), everything included: actuator law every
  physics substep, observation, reward, autoreset. One env step = ``decimation`` substeps.
* MuJoCo ceilings (:class:`ReplayCeiling`), no environment: the motion of the ``env`` row
  recorded (each control step's starting states and the mean joint torques the env applied)
  and replayed from those states with the model's actuators off and the torques held
  constant, so the physics visits the same contacts and flight phases and does strictly less
  work than the env:
  ``mj_step loop``: a bare Python loop of ``mj_setState`` and ``mujoco.mj_step`` over the
  robots split across the same number of threads (``concurrent.futures``; mj_step releases
  the GIL), and
  ``rollout``: ``mujoco.rollout`` doing ``decimation`` steps per robot in C++, the faster of
  MuJoCo's own thread pool (``Rollout(nthread=threads)``) and the env's
  :class:`~cpg_actor.robots.common.threaded_rollout.ThreadedRollout` (the calling thread and
  helpers), both timed.
  Until 27 Nov 2026 the ceilings stepped one snapshot of states (50 control steps in) over
  and over; what a step costs depends on the phase of the hop (contacts), by up to 1.5x, so
  that measured one phase, not the motion.
* PyBullet ceiling: ``stepSimulation`` in a bare loop on the same worlds of N robots.

Throughput is env steps (robot x control step) per second; a ceiling's is its substeps per
second divided by ``decimation``. Each figure is the best of ``--repeats`` timed blocks
(the machine may be shared); env and ceilings are measured interleaved.

Run: ``python benchmarks/env_throughput.py`` (writes ``benchmarks/results/env_throughput.md``);
``--quick`` for a short check (prints only, N <= 64), ``--max-n`` to cap N.
"""

from __future__ import annotations

import argparse
import copy
import datetime
import os
import platform
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from cpg_actor.machine import cpu_model, load_average, usable_cores
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.vector import HopperVectorEnv

DEFAULT_OUT = Path(__file__).resolve().parent / "results" / "env_throughput.md"
SIZES = (1, 16, 64, 256, 1024)
ENV_STEPS_BUDGET = {"mujoco": 20_000, "pybullet": 4_000}  # robot-steps per timed block


def machine_description() -> list[str]:
    import gymnasium
    import mujoco

    from cpg_actor.robots.hopper.backends.pybullet_backend import pybullet

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


WARMUP_STEPS = 50  # control steps of hopping before anything is timed or recorded


class MotionRecorder:
    """Records the control steps of a MuJoCo backend (:class:`~cpg_actor.robots.hopper.backends.
    mujoco_backend.MujocoBackend`): the robots' full physics state before each and the mean
    joint torques it applied (what ``track`` returns), the motion a :class:`ReplayCeiling`
    replays. It wraps ``track`` on this one backend until :meth:`stop`; it copies a (K, 8)
    state per control step and changes nothing that is simulated."""

    def __init__(self, backend) -> None:
        self.backend = backend
        self.states: list[np.ndarray] = []
        self.torques: list[np.ndarray] = []
        self.substeps = 0  # per control step, as track() was called
        self._track = backend.track
        backend.track = self._record  # an instance attribute: shadows the method

    def _record(self, desired: np.ndarray, substeps: int, push=None) -> np.ndarray:
        self.states.append(self.backend.get_state())
        self.substeps = substeps
        torque = self._track(desired, substeps, push)
        self.torques.append(np.array(torque, dtype=np.float64))
        return torque

    @property
    def steps(self) -> int:
        """Control steps recorded so far."""
        return len(self.states)

    def slice(self, start: int) -> tuple[np.ndarray, np.ndarray]:
        """The states (T, K, nstate) and torques (T, K, 2) recorded from control step
        ``start`` on, recording going on."""
        return np.stack(self.states[start:]), np.stack(self.torques[start:])

    def stop(self) -> tuple[np.ndarray, np.ndarray]:
        """Unwrap ``track``; the recorded states (T, K, nstate) and torques (T, K, 2)."""
        del self.backend.track
        return np.stack(self.states), np.stack(self.torques)


class ReplayCeiling:
    """The raw physics of a recorded motion, no environment: from each recorded state, the
    control step's ``decimation`` substeps with the model's actuators off and the recorded
    mean joint torques held constant (no actuator law, observation, reward or Python
    between substeps). So it steps the states the env visited (its contacts, its flight
    phases), doing strictly less work per substep than the env.

    * :meth:`rollout_rate`: ``mujoco.rollout`` of all K robots per control step, the faster
      of MuJoCo's thread pool (``Rollout(nthread=threads)``) and the env's own
      :class:`~cpg_actor.robots.common.threaded_rollout.ThreadedRollout`
      (:meth:`rollout_rates`: each of the two).
    * :meth:`loop_rate`: a Python loop of ``mj_setState`` and ``mujoco.mj_step`` over the
      robots, split across ``threads`` threads (``mj_step`` releases the GIL).
    """

    def __init__(self, model, states: np.ndarray, torques: np.ndarray, decimation: int,
                 threads: int) -> None:  # fmt: skip
        import mujoco
        from mujoco import rollout

        from cpg_actor.robots.common.threaded_rollout import ThreadedRollout

        self.mujoco = mujoco
        self.model = copy.copy(model)
        self.model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_ACTUATION.value
        self.states = np.ascontiguousarray(states, dtype=np.float64)
        self.torques = torques
        self.decimation = decimation
        self.threads = max(1, threads)
        steps, robots = states.shape[:2]
        self.control = np.zeros((steps, robots, decimation, self.model.nv))
        self.control[..., 1:3] = torques[:, :, None, :]  # hip and knee (dof 0: the rail)
        self.out = np.empty((robots, decimation, states.shape[-1]))
        self.roller = rollout.Rollout(nthread=self.threads if self.threads > 1 else 0)
        self.roll_datas = [mujoco.MjData(self.model) for _ in range(self.threads)]
        self.threaded = ThreadedRollout(self.model, robots, self.threads)

    def rollout_rates(self) -> dict[str, float]:
        """Control steps per second of ``mujoco.rollout`` over the whole recorded motion,
        stepped by MuJoCo's thread pool (``pool``) and by the env's ``ThreadedRollout``
        (``threaded``)."""
        steps, robots = self.states.shape[:2]
        spec = self.mujoco.mjtState.mjSTATE_QFRC_APPLIED.value
        chunk = max(1, robots // (4 * self.threads))

        def pool() -> None:
            for t in range(steps):
                self.roller.rollout(
                    [self.model] * robots, self.roll_datas, self.states[t], self.control[t],
                    control_spec=spec, skip_checks=True, nstep=self.decimation,
                    initial_warmstart=None, state=self.out, sensordata=None, chunk_size=chunk,
                )  # fmt: skip

        def threaded() -> None:
            for t in range(steps):
                self.threaded.rollout(
                    self.states[t], self.control[t], self.out, None, spec, self.decimation
                )

        work = steps * robots
        return {"pool": best_rate(pool, work, 1), "threaded": best_rate(threaded, work, 1)}

    def rollout_rate(self) -> float:
        """Control steps per second of ``mujoco.rollout`` over the whole recorded motion."""
        return max(self.rollout_rates().values())

    def loop_rate(self) -> float:
        """Control steps per second of a bare ``mj_step`` loop over a quarter of the motion."""
        mujoco, model = self.mujoco, self.model
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS.value
        steps = max(1, len(self.states) // 4)

        robots = self.states.shape[1]
        chunks = [range(i, robots, self.threads) for i in range(self.threads)]

        def loop(rows: range) -> None:
            data = mujoco.MjData(model)  # one per thread: each robot's state is set first
            for t in range(steps):
                for i in rows:
                    mujoco.mj_setState(model, data, self.states[t, i], spec)
                    data.qfrc_applied[1:3] = self.torques[t, i]
                    for _ in range(self.decimation):
                        mujoco.mj_step(model, data)

        if self.threads == 1:
            return best_rate(lambda: loop(chunks[0]), steps * robots, 1)
        with ThreadPoolExecutor(self.threads) as pool:
            return best_rate(lambda: list(pool.map(loop, chunks)), steps * robots, 1)

    def close(self) -> None:
        self.roller.close()
        self.threaded.close()


def bench_size(sim: str, num_envs: int, repeats: int, budget: int) -> dict:
    """One row: the env and, for MuJoCo, the ceilings replaying the env's own motion."""
    config = HopperConfig(sim=sim)
    env = HopperVectorEnv(num_envs, config)
    steps = max(5, min(2000, budget // num_envs))
    actions = hopping_actions(num_envs, WARMUP_STEPS + steps, config.control_dt)

    def start() -> None:  # the same motion every time: reset, get the robots hopping
        env.reset(seed=0)
        for t in range(WARMUP_STEPS):
            env.step(actions[t])

    def run_env() -> None:
        for t in range(steps):
            env.step(actions[WARMUP_STEPS + t])

    backend = env.sim.backend
    row = {"sim": sim, "N": num_envs, "threads": env.num_threads, "steps": steps}
    if sim == "mujoco":
        start()
        recorder = MotionRecorder(backend)
        run_env()
        ceiling = ReplayCeiling(backend.model, *recorder.stop(), config.decimation,
                                env.num_threads)  # fmt: skip
        env_rate = loop_rate = roll_rate = 0.0
        for _ in range(repeats):  # interleaved: a busy neighbour affects them all alike
            start()
            env_rate = max(env_rate, best_rate(run_env, steps * num_envs, 1))
            loop_rate = max(loop_rate, ceiling.loop_rate())
            roll_rate = max(roll_rate, ceiling.rollout_rate())
        ceiling.close()
        row.update(env=env_rate, loop=loop_rate, rollout=roll_rate)
    else:
        from cpg_actor.robots.hopper.backends.pybullet_backend import ROBOTS_PER_WORLD

        first_of_each_world = range(0, num_envs, ROBOTS_PER_WORLD)
        clients = [backend.handle(i)[0] for i in first_of_each_world]

        def run_bare() -> None:
            for _ in range(steps * config.decimation):
                for client in clients:
                    client.stepSimulation()

        start()
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
        "MuJoCo's ceilings replay the env row's own motion: from each control step's recorded "
        "states, with the model's actuators off and the mean joint torques the env applied held "
        "constant (no actuator law, no observation).",
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
