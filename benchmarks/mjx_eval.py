"""The evaluation during training on MJX: the device loop of ``cpg_actor.training.evaluation`` (the
env's tensor face, no per-step copies to the host) against the numpy loop it replaced (the
env's Gymnasium face, every output copied to numpy at every step), in the same run, taking
turns. Both evaluate the same untrained policy on the same envs (``eval_episodes`` envs of
their own, the policy's mean action, to the end of the episode) and must give the same
numbers; the script checks that, times each evaluation (wall time, and the process's CPU time,
which other processes on the machine disturb less) and counts its host reads
(``cpg_actor.host_reads``: on a GPU each is a wait for the device). The ratios are the median
of each round's before / after.

    python benchmarks/mjx_eval.py [--agent cpg-actor] [--robot hopper] [--episodes 5]
        [--steps 500] [--rounds 7] [--output benchmarks/results/mjx_eval_cpu.md]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from bench_report import measured, write
from cpg_actor.config import TrainConfig, apply_dict
from cpg_actor.host_reads import host_reads
from cpg_actor.robots.hopper.mjx.dynamics import jax
from cpg_actor.robots.registry import ROBOTS
from cpg_actor.training.build import make_env
from cpg_actor.training.evaluation import evaluate
from cpg_actor.training.policy import Policy
from cpg_actor.training.runner import Runner


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--agent", default="cpg-actor")
    on_mjx = [name for name, robot in ROBOTS.items() if "mjx" in robot.simulators]
    parser.add_argument("--robot", default="hopper", choices=on_mjx)
    parser.add_argument("--episodes", type=int, default=5, help="eval_episodes (the envs)")
    parser.add_argument("--steps", type=int, default=500, help="control steps per episode")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--output", default="benchmarks/results/mjx_eval_cpu.md")
    args = parser.parse_args()

    # the policy where the env is (CUDA when torch sees it), as the gpu preset's
    config = TrainConfig(agent=args.agent, num_envs=args.episodes, eval_interval=0, device="auto")
    apply_dict(config, {"robot": args.robot}, "")
    apply_dict(config, {"env": {"sim": "mjx"}}, "")
    if hasattr(config.env, "episode_seconds"):  # the quadrupeds'
        config.env.episode_seconds = args.steps * config.env.control_dt
    else:
        config.env.episode_steps = args.steps
    runner = Runner(config, tensorboard=False)  # its env: the eval env's batch, one compile
    env = make_env(config, runner.robot, args.episodes, 1)
    bounds = runner.policy.action_low, runner.policy.action_high
    policy = Policy(runner.agent, runner.normalizer, *bounds)
    control_dt = float(config.env.control_dt)

    def run(on_device: bool) -> dict:
        return evaluate(policy, env, seed=0, control_dt=control_dt, max_steps=args.steps,
                        traces=False, on_device=on_device)  # fmt: skip

    results = {mode: run(mode) for mode in (False, True)}  # compiles; the numbers compared
    for key in ("episode_return", "length", *results[False]["metric_names"]):
        np.testing.assert_array_equal(results[True][str(key)], results[False][str(key)])
    reads = {}
    for mode in (False, True):
        with host_reads() as reads[mode]:
            run(mode)
    wall = {False: [], True: []}
    cpu = {False: [], True: []}
    for _ in range(args.rounds):
        for mode in (False, True):
            start, start_cpu = time.perf_counter(), time.process_time()
            run(mode)
            wall[mode].append(time.perf_counter() - start)
            cpu[mode].append(time.process_time() - start_cpu)
    runner.close()
    env.close()

    wall_ratio = float(np.median(np.divide(wall[False], wall[True])))
    cpu_ratio = float(np.median(np.divide(cpu[False], cpu[True])))
    steps = int(results[True]["length"].max())
    command = (
        f"python benchmarks/mjx_eval.py --agent {args.agent} --robot {args.robot} "
        f"--episodes {args.episodes} --steps {args.steps} --rounds {args.rounds}"
    )
    names = {False: "numpy loop (before)", True: "device loop (after)"}
    lines = [
        "# One evaluation during training on MJX: the device loop against the numpy loop",
        "",
        measured(command) + f", MJX on JAX's {jax.devices()[0].platform} backend, "
        f"torch on {runner.device}.",
        "",
        f"`{args.agent}` (untrained) on the {args.robot}, {args.episodes} envs, episodes of "
        f"{steps} control steps; both loops gave the same returns, lengths and metrics. "
        f"Wall and process CPU time of one evaluation, median (and range) of {args.rounds} "
        "rounds, the loops taking turns; host reads per evaluation (`cpg_actor.host_reads`).",
        "",
        "| loop | wall | CPU | host reads |",
        "| --- | ---: | ---: | ---: |",
        *(
            f"| {names[m]} | {np.median(wall[m]):.2f} s ({min(wall[m]):.2f}-{max(wall[m]):.2f}) "
            f"| {np.median(cpu[m]):.2f} s ({min(cpu[m]):.2f}-{max(cpu[m]):.2f}) "
            f"| {len(reads[m]):,} |"
            for m in (False, True)
        ),
        "",
        f"Before / after, median of the rounds' ratios: {wall_ratio:.2f}x wall time, "
        f"{cpu_ratio:.2f}x CPU time.",
        "",
    ]
    write(args.output, lines)


if __name__ == "__main__":
    main()
