"""Where a rollout step of the ``gpu`` preset spends its time, on the device it runs on.

    python benchmarks/profile_collect.py [--num-envs 4096] [--agent cpg-actor]
        [--output benchmarks/results/profile_collect.md]

One ``Runner.collect`` (``ppo.num_steps`` control steps of every env) after a warm-up
iteration, split three ways, each timed on its own with the device synchronised:

* the env step alone (``env.step`` of the policy's last actions: physics, reward, autoreset);
* the policy alone (``Policy.act``: normaliser, agent, sampling);
* the whole collect step, whose rest is storage, reward normaliser, bootstrapping and the
  episode log;

then ``torch.profiler`` over one more collect: the host-side calls that launch or wait for
device work (kernel launches, synchronisations, copies), per control step, and the operators
with the most device time. On a CPU the same script runs with CPU times only.
"""

from __future__ import annotations

import argparse
import time

import torch
from torch.profiler import ProfilerActivity, profile

from bench_report import measured, write
from cpg_actor.config import TrainConfig, apply_dict
from cpg_actor.config.presets import preset_values
from cpg_actor.training.runner import Runner

HOST_CALLS = ("cudaLaunchKernel", "cuLaunchKernel", "cudaStreamSynchronize",
              "cudaDeviceSynchronize", "cudaMemcpyAsync", "cudaEventSynchronize")  # fmt: skip


def timed(step, repeats: int, sync) -> float:
    """Milliseconds per call of ``step()``, synchronised, after a warm-up call."""
    step()
    sync()
    start = time.perf_counter()
    for _ in range(repeats):
        step()
    sync()
    return (time.perf_counter() - start) / repeats * 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--num-envs", type=int, default=4096)
    parser.add_argument("--agent", default="cpg-actor")
    parser.add_argument("--device", default="auto")
    parser.add_argument("--output", default="benchmarks/results/profile_collect.md")
    args = parser.parse_args()

    config = TrainConfig(agent=args.agent)
    apply_dict(config, preset_values("gpu"), "")
    config.num_envs, config.device, config.eval_interval = args.num_envs, args.device, 0
    config.total_steps = 4 * config.steps_per_iteration
    runner = Runner(config, run_dir=None, tensorboard=False)
    cuda = runner.device.type == "cuda"
    sync = torch.cuda.synchronize if cuda else (lambda: None)
    steps = config.ppo.num_steps
    try:
        runner.start_episodes()
        runner.collect()
        runner.update()
        acted = runner.policy.act(runner.rollout.obs, deterministic=False, tensor_action=True)
        env_ms = timed(lambda: runner.env.step(acted.action), steps, sync)
        act_ms = timed(
            lambda: runner.policy.act(runner.rollout.obs, deterministic=False, tensor_action=True),
            steps,
            sync,
        )
        collect_ms = timed(runner.collect, 1, sync) / steps
        activities = [ProfilerActivity.CPU] + ([ProfilerActivity.CUDA] if cuda else [])
        with profile(activities=activities) as prof:
            runner.collect()
            sync()
    finally:
        runner.close()

    events = prof.key_averages()
    host = {e.key: e.count / steps for e in events if e.key in HOST_CALLS}
    device_attr = "self_device_time_total" if cuda else "self_cpu_time_total"
    top = sorted(events, key=lambda e: getattr(e, device_attr, 0.0), reverse=True)[:15]
    where = f"{torch.cuda.get_device_name()}" if cuda else "the CPU"
    lines = [
        "# One rollout step of the `gpu` preset, taken apart",
        "",
        measured(
            f"python benchmarks/profile_collect.py --num-envs {args.num_envs} --agent {args.agent}"
        )
        + f", on {where} (torch {torch.__version__}).",
        "",
        f"{args.agent}, {args.num_envs:,} envs; milliseconds per control step of every env:",
        "",
        "| part | ms |",
        "| --- | ---: |",
        f"| env step alone (`env.step`) | {env_ms:.2f} |",
        f"| policy alone (`Policy.act`) | {act_ms:.2f} |",
        f"| whole collect step | {collect_ms:.2f} |",
        f"| rest (storage, normalisers, bootstrap, episode log) | "
        f"{collect_ms - env_ms - act_ms:.2f} |",
        "",
        "Host calls per control step (profiler): "
        + (", ".join(f"{k} {v:.0f}" for k, v in sorted(host.items())) or "none recorded")
        + ".",
        "",
        f"Operators with the most {'device' if cuda else 'CPU'} time in one collect "
        f"({steps} steps), total ms:",
        "",
        "| operator | calls | ms |",
        "| --- | ---: | ---: |",
    ]
    lines += [
        f"| `{e.key[:70]}` | {e.count} | {getattr(e, device_attr, 0.0) / 1e3:.2f} |" for e in top
    ]
    write(args.output, lines + [""])


if __name__ == "__main__":
    main()
