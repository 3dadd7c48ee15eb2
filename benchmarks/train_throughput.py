"""End-to-end PPO training throughput per agent, split into simulation / policy inference /
learning, next to the raw simulator ceiling (same env, same number of envs, same process).

    python benchmarks/train_throughput.py [--num-envs 64] [--iterations 5] [--sim mujoco]
        [--output benchmarks/results/train_throughput.md]
"""

from __future__ import annotations

import argparse
import datetime
import time
from pathlib import Path

import numpy as np
import torch

from cpg_actor.config import TrainConfig
from cpg_actor.machine import cpu_model, load_average, usable_cores
from cpg_actor.runner import Runner

AGENTS = ("mlp", "cpg-actor", "cpg-actor-open-loop")


def simulator_ceiling(config: TrainConfig, steps: int) -> float:
    """Control steps per second of ``env.step`` alone, with the nominal pose as action."""
    from cpg_actor.agents import get_agent_spec

    env = get_agent_spec(config.agent).make_env(config.num_envs, config.env, config.env_threads)
    try:
        env.reset(seed=0)
        action = np.tile(np.array([0.4, -0.8], dtype=np.float32), (config.num_envs, 1))
        env.step(action)
        start = time.perf_counter()
        for _ in range(steps):
            env.step(action)
        return steps * config.num_envs / (time.perf_counter() - start)
    finally:
        env.close()


def training_throughput(config: TrainConfig, iterations: int) -> dict[str, float]:
    """Run 1 warm-up iteration, then ``iterations`` timed ones."""
    config.total_steps = (iterations + 1) * config.steps_per_iteration
    runner = Runner(config, run_dir=None, tensorboard=False)
    totals = {"simulation": 0.0, "inference": 0.0, "learning": 0.0, "wall": 0.0}
    try:
        runner.start_episodes()
        for i in range(iterations + 1):
            start = time.perf_counter()
            info = runner.collect()
            collected = time.perf_counter()
            runner.ppo.update(runner.storage)
            end = time.perf_counter()
            if i == 0:
                continue
            totals["simulation"] += info["simulation_time"]
            totals["inference"] += collected - start - info["simulation_time"]
            totals["learning"] += end - collected
            totals["wall"] += end - start
    finally:
        runner.close()
    steps = iterations * config.steps_per_iteration
    return {"SPS": steps / totals["wall"], **{k: v / totals["wall"] for k, v in totals.items()}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--num-envs", type=int, default=64)
    parser.add_argument("--iterations", type=int, default=5)
    parser.add_argument("--sim", default="mujoco", choices=("mujoco", "pybullet"))
    parser.add_argument("--agents", nargs="+", default=list(AGENTS))
    parser.add_argument("--output", default="benchmarks/results/train_throughput.md")
    args = parser.parse_args()

    rows = []
    base = TrainConfig(num_envs=args.num_envs)
    base.env.sim = args.sim
    ceiling = simulator_ceiling(base, steps=200)
    print(f"simulator ceiling ({args.sim}, {args.num_envs} envs): {ceiling:,.0f} steps/s")
    for agent in args.agents:
        config = TrainConfig(agent=agent, num_envs=args.num_envs)
        config.env.sim = args.sim
        result = training_throughput(config, args.iterations)
        rows.append((agent, result))
        print(
            f"{agent:22s} {result['SPS']:8,.0f} SPS  simulation {result['simulation']:.0%}  "
            f"inference {result['inference']:.0%}  learning {result['learning']:.0%}"
        )

    config = TrainConfig()
    lines = [
        "# Training throughput",
        "",
        f"Measured {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC with "
        f"`python benchmarks/train_throughput.py --num-envs {args.num_envs} "
        f"--iterations {args.iterations} --sim {args.sim}`.",
        "",
        f"Machine: {cpu_model()}, {usable_cores()} usable cores (load {load_average()}), "
        f"torch {torch.__version__} CPU, torch threads {config.torch_threads}, "
        f"env threads {config.env_threads or 'env default'}.",
        f"Batch per iteration: {args.num_envs} envs x {config.ppo.num_steps} steps; "
        f"{config.ppo.num_epochs} epochs x {config.ppo.num_minibatches} minibatches.",
        "",
        f"Raw simulator ceiling (`env.step` alone, constant action): **{ceiling:,.0f}** "
        "control steps/s.",
        "",
        "| agent | training SPS | simulation | policy inference | learning | fraction of ceiling |",
        "| --- | ---: | ---: | ---: | ---: | ---: |",
    ]
    for agent, r in rows:
        lines.append(
            f"| {agent} | {r['SPS']:,.0f} | {r['simulation']:.0%} | {r['inference']:.0%} | "
            f"{r['learning']:.0%} | {r['SPS'] / ceiling:.0%} |"
        )
    lines += [
        "",
        "Shares are of the wall time of an iteration; inference includes the agent step, the",
        "observation normaliser, rollout storage, episode bookkeeping and GAE.",
        "",
    ]
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text("\n".join(lines))
    print(f"written {args.output}")


if __name__ == "__main__":
    main()
