"""A robot's MJX throughput on JAX's device (an NVIDIA GPU where there is one, else JAX's
CPU backend), per batch size: the physics alone, the env, and end-to-end PPO training per agent
(the ``gpu`` preset, networks and PPO on the same device), with the device named.

    python benchmarks/gpu_throughput.py [--robot hopper] [--envs 1024 4096 32768 131072]
        [--agents cpg-actor cpg-actor-open-loop mlp] [--iterations 3] [--seeds K]
        [--set KEY=VALUE] [--output benchmarks/results/gpu_throughput.md]

* physics: ``decimation`` x ``mjx.step`` per control step for every robot, the actuator law at
  every substep: the ceiling of this env on this device;
* env: the MJX env's ``step_tensors`` with torch actions (physics, task, autoreset, DLPack both
  ways): the env stepped with nothing else;
* both driving every robot through an open-loop gait with a random phase per robot (the
  hopper: a 2 Hz hop; a quadruped: a 2 Hz trot of its hips and knees about its nominal pose):
  a moving robot costs the contact solver more than a still one;
* training: ``Runner.collect`` + ``Runner.update`` with the ``gpu`` preset (its rollout of 24
  steps, 5 epochs of 4 minibatches) at each batch size, after one warm-up iteration (the JIT
  and ``torch.compile``), and the paper's budget (5 variants x 5 seeds x 20M steps)
  extrapolated from it, run after run on one device.

It installs nothing and reads nothing from the network; every figure is measured in this run.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch

from bench_report import measured, write
from cpg_actor.config import compose_config
from cpg_actor.machine import cpu_model, usable_cores
from cpg_actor.robots.common.mjx_runtime import load
from cpg_actor.robots.registry import get_robot
from cpg_actor.training.many_seeds import SeedGroup
from cpg_actor.training.runner import Runner

jax, _ = load()

AGENTS = ("cpg-actor", "cpg-actor-open-loop", "mlp")
PAPER_BUDGET = 5 * 5 * 20_000_000  # control steps: 5 variants x 5 seeds x 20M
CPU_CEILING_ROBOTS = 4096  # the CPU ceiling is measured with at most this many robots
OVERRIDES: list[str] = []  # --set values over the gpu preset, for every config of the run


def device_name() -> str:
    device = jax.devices()[0]
    if device.platform == "cpu":
        return f"JAX CPU backend on {cpu_model()} ({usable_cores()} usable cores); no GPU"
    return f"{device.device_kind} (JAX {device.platform}:{device.id})"


def timed(step, repeats: int) -> float:
    """Seconds per call of ``step()`` (which blocks until its work is done), after a warm-up."""
    step()
    start = time.perf_counter()
    for _ in range(repeats):
        step()
    return (time.perf_counter() - start) / repeats


def gpu_config(robot: str, agent: str = "cpg-actor"):
    """The ``gpu`` preset's config of ``agent`` on ``robot``, as ``cpg-actor train --preset gpu
    --robot ROBOT --agent AGENT`` composes it, with the run's ``--set`` values."""
    return compose_config("gpu", values={"robot": robot, "agent": agent}, overrides=OVERRIDES)


def gait(robot: str, env, num_envs: int) -> list[np.ndarray]:
    """One 2 Hz period (50 control steps of 10 ms) of desired joint positions, a random phase
    per robot: the hopper's squat-and-extend of the agreement tests (0.35 / 0.7 rad on HFE /
    KFE), a quadruped's trot (diagonal legs together; 0.3 / 0.6 rad on hip / knee pitch)."""
    phase = np.random.default_rng(0).uniform(0, 2 * np.pi, (num_envs, 1))
    steps = [2 * np.pi * k / 50 + phase for k in range(50)]
    if robot == "hopper":
        return [(np.array([0.4, -0.8]) + np.array([0.35, -0.7]) * np.sin(t)).astype(np.float32)
                for t in steps]  # fmt: skip
    nominal = np.asarray(env.dynamics.quadruped.nominal_pose, dtype=np.float64)
    swing = np.tile([0.0, 0.3, -0.6], 4)
    legs = np.repeat([0.0, np.pi, np.pi, 0.0], 3)  # FL, FR, RL, RR: diagonals in phase
    return [(nominal + swing * np.sin(t + legs)).astype(np.float32) for t in steps]


def physics_and_env(robot: str, num_envs: int, repeats: int) -> dict[str, float]:
    """Both driven by the open-loop gait of :func:`gait`. The contact solver works harder on a
    moving robot than on a still one (3-4x on the CPU), so constant actions would flatter it."""
    config = gpu_config(robot)
    env = get_robot(robot).make(num_envs, config.env, None)
    try:
        env.reset_tensors(seed=0)
        control = jax.jit(jax.vmap(env.dynamics.control))
        draws = gait(robot, env, num_envs)
        desired = [jax.device_put(d, env.jax_device) for d in draws]
        actions = [torch.from_numpy(d).to(env.device) for d in draws]
        data, count = [env.jax_state.data], [0]

        def physics():
            count[0] += 1
            out = control(data[0], desired[count[0] % 50])
            data[0] = out[0]
            out[0].qpos.block_until_ready()

        def env_step():
            count[0] += 1
            out = env.step_tensors(actions[count[0] % 50])
            if out.obs.is_cuda:
                torch.cuda.synchronize()

        return {
            "physics": num_envs / timed(physics, repeats),
            "env": num_envs / timed(env_step, repeats),
        }
    finally:
        env.close()


def cpu_ceiling(robot: str, num_envs: int) -> float:
    """``mujoco.rollout`` on this machine's CPU cores, same MJCF and robots (env_throughput;
    the hopper's only)."""
    if robot != "hopper":
        return float("nan")
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    from env_throughput import bench_size

    return bench_size("mujoco", num_envs, repeats=2, budget=50_000)["rollout"]


def training(
    robot: str, agent: str, num_envs: int, iterations: int, device: str
) -> dict[str, float]:
    config = gpu_config(robot, agent)
    config.num_envs, config.device, config.eval_interval = num_envs, device, 0
    config.total_steps = (iterations + 1) * config.steps_per_iteration
    runner = Runner(config, run_dir=None, tensorboard=False)
    sync = torch.cuda.synchronize if runner.device.type == "cuda" else (lambda: None)
    collect = update = 0.0
    try:
        runner.start_episodes()
        for i in range(iterations + 1):
            start = time.perf_counter()
            runner.collect()
            sync()
            collected = time.perf_counter()
            runner.update()
            sync()
            if i > 0:
                collect += collected - start
                update += time.perf_counter() - collected
    finally:
        runner.close()
    samples = iterations * config.steps_per_iteration
    return {"SPS": samples / (collect + update), "collect_share": collect / (collect + update)}


def group_training(
    robot: str, agent: str, num_envs: int, seeds: int, iterations: int, device: str
) -> dict[str, float]:
    """``seeds`` runs of ``agent`` in one process (:class:`SeedGroup`), ``num_envs`` each:
    their control steps per second together, after one warm-up iteration."""
    config = gpu_config(robot, agent)
    config.num_envs, config.device, config.eval_interval = num_envs, device, 0
    config.total_steps = (iterations + 1) * config.steps_per_iteration
    group = SeedGroup(config, list(range(seeds)))
    sync = torch.cuda.synchronize if group.runners[0].device.type == "cuda" else (lambda: None)
    try:
        group.start()
        group.train_iteration()
        sync()
        start = time.perf_counter()
        for _ in range(iterations):
            group.train_iteration()
        sync()
        seconds = time.perf_counter() - start
    finally:
        group.close()
    return {"SPS": seeds * iterations * config.steps_per_iteration / seconds}


def report(args, name: str, rows: list) -> None:
    """Write the table of the sizes measured so far (after each size: a run cut short by a time
    limit still leaves its table)."""
    command = f"python benchmarks/gpu_throughput.py --robot {args.robot} --envs "
    command += " ".join(map(str, args.envs))
    command += f" --agents {' '.join(args.agents)} --iterations {args.iterations}"
    command += f" --seeds {args.seeds}" if args.seeds > 1 else ""
    command += "".join(f" --set {value}" for value in args.set)
    config = gpu_config(args.robot)
    substeps = f"{config.env.decimation} physics substeps of {config.env.physics_dt * 1e3:g} ms"
    group = f"{args.seeds} seeds in one process" if args.seeds > 1 else None
    lines = [
        f"# MJX throughput: {args.robot}",
        "",
        measured(command) + ".",
        "",
        f"Device: **{name}**; JAX {jax.__version__}, torch {torch.__version__}"
        + (f" on {torch.cuda.get_device_name()}" if torch.cuda.is_available() else "")
        + ".",
        "",
        f"Control steps per second (one control step = {substeps}); physics and env drive",
        "every robot through an open-loop 2 Hz gait (random phase per robot).",
        "",
        "| envs | physics | env | "
        + " | ".join(f"training {a}" for a in args.agents)
        + (f" | {group}, {args.agents[0]}: together (x one seed)" if group else "")
        + " | MuJoCo C on the CPU |",
        "| ---: | ---: | ---: | " + " | ".join("---:" for _ in args.agents)
        + (" | ---:" if group else "") + " | ---: |",
    ]  # fmt: skip
    for num_envs, speeds, trained in rows:
        cells = [f"{trained[a]['SPS']:,.0f} ({trained[a]['SPS'] / speeds['env']:.0%})"
                 for a in args.agents]  # fmt: skip
        if group:
            together = trained["group"]["SPS"]
            cells.append(f"{together:,.0f} (x{together / trained[args.agents[0]]['SPS']:.2f})")
        cpu = "-" if np.isnan(speeds["cpu"]) else f"{speeds['cpu']:,.0f}"
        lines.append(
            f"| {num_envs:,} | {speeds['physics']:,.0f} | {speeds['env']:,.0f} | "
            + " | ".join(cells) + f" | {cpu} |"
        )  # fmt: skip
    best = max(rows, key=lambda row: row[2][args.agents[0]]["SPS"])
    sps = best[2][args.agents[0]]["SPS"]
    lines += [
        "",
        f"MuJoCo C on the CPU: `mujoco.rollout` of the same MJCF on this machine's "
        f"{usable_cores()} CPU cores, in the same run (the CPU simulators' ceiling), with as "
        f"many robots up to {CPU_CEILING_ROBOTS:,} (the rate no longer grows past a few hundred "
        "robots per core, and the CPU env that sets the robots hopping first takes minutes at "
        "more)."
        if args.robot == "hopper"
        else "MuJoCo C on the CPU: not measured here for a quadruped "
        "(`benchmarks/quadruped_train_throughput.py` measures its CPU ceiling).",
        "",
        "Training: the `gpu` preset at each size (percent: of the env's own rate); "
        + (
            f"{group}: a `SeedGroup` of {args.seeds} `{args.agents[0]}` runs, each with the "
            "row's envs, over one env of as many times the robots, their control steps summed "
            "(x: over one seed's rate in its own process); "
            if group
            else ""
        )
        + "collection",
        "share of the training time at the largest size: "
        + ", ".join(f"{a} {rows[-1][2][a]['collect_share']:.0%}" for a in args.agents)
        + ".",
        "",
        f"The paper's budget (5 variants x 5 seeds x 20M = {PAPER_BUDGET / 1e6:,.0f}M steps) at "
        f"{args.agents[0]}'s best rate here ({sps:,.0f} SPS at {best[0]:,} envs), one run after "
        f"another on this device: **{PAPER_BUDGET / sps / 3600:,.1f} h**.",
        "",
    ]
    write(args.output, lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="hopper", help="a robot with an MJX env")
    parser.add_argument("--envs", type=int, nargs="+", default=[1024, 4096, 32768, 131072])
    parser.add_argument("--agents", nargs="+", default=list(AGENTS))
    parser.add_argument("--iterations", type=int, default=3, help="timed training iterations")
    parser.add_argument("--repeats", type=int, default=20, help="timed env steps per size")
    parser.add_argument("--device", default="auto", help="torch device for training (auto)")
    parser.add_argument(
        "--seeds", type=int, default=1, help="K > 1: also K seeds of the first agent in one process"
    )
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a config value over the gpu preset (repeatable), e.g. "
                        "env.floor_contacts=all")  # fmt: skip
    parser.add_argument("--output", default="benchmarks/results/gpu_throughput.md")
    args = parser.parse_args()
    OVERRIDES.extend(args.set)

    name = device_name()
    print(f"device: {name}", flush=True)
    rows, ceilings = [], {}
    for num_envs in args.envs:
        speeds = physics_and_env(args.robot, num_envs, args.repeats)
        robots = min(num_envs, CPU_CEILING_ROBOTS)
        if robots not in ceilings:
            ceilings[robots] = cpu_ceiling(args.robot, robots)
        speeds["cpu"] = ceilings[robots]
        print(f"{num_envs} envs: {speeds}", flush=True)
        trained = {}
        for agent in args.agents:
            trained[agent] = training(args.robot, agent, num_envs, args.iterations, args.device)
            print(f"  {agent}: {trained[agent]}", flush=True)
        if args.seeds > 1:
            trained["group"] = group_training(
                args.robot, args.agents[0], num_envs, args.seeds, args.iterations, args.device
            )
            print(f"  {args.seeds} seeds in one process: {trained['group']}", flush=True)
        rows.append((num_envs, speeds, trained))
        report(args, name, rows)


if __name__ == "__main__":
    main()
