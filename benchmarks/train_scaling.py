"""Training throughput against the number of CPU cores: does training get faster with cores?

    python benchmarks/train_scaling.py [--cores 2 8 all] [--num-envs 64 1024]
        [--agent cpg-actor] [--output benchmarks/results/train_scaling.md]

For each core count C and number of envs N, a subprocess pinned to C cores
(``os.sched_setaffinity``) trains the throughput preset with N envs: the simulator's threads
follow the usable cores (at least 8 robots per thread) and PyTorch gets C threads. It
reports the training SPS after a warm-up iteration, next to the physics ceiling of the same
motion (``mujoco.rollout`` replaying the control steps the training visited, on the same C
cores: ``train_throughput.py``), both measured in the same subprocess.
Core counts above the machine's are skipped.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def measure(agent: str, num_envs: int, iterations: int) -> dict:
    """In this (pinned) process: training SPS and the physics ceiling for ``num_envs``."""
    import torch

    sys.path.insert(0, str(HERE))
    from cpg_actor.machine import usable_cores
    from train_throughput import measure as train_measure

    cores = usable_cores()
    torch.set_num_threads(cores)
    result = train_measure(
        agent, "throughput", iterations, compile=True, num_envs=num_envs, torch_threads=cores,
        ceiling=True,
    )  # fmt: skip
    result["cores"] = cores
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cores", nargs="+", default=["2", "8", "all"])
    parser.add_argument("--num-envs", nargs="+", type=int, default=[64, 1024])
    parser.add_argument("--agent", default="cpg-actor")
    parser.add_argument("--iterations", type=int, default=3)
    parser.add_argument("--output", default=str(HERE / "results" / "train_scaling.md"))
    parser.add_argument("--child", nargs=2, type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:  # one measurement, printed as JSON
        print(json.dumps(measure(args.agent, args.child[1], args.iterations)))
        return

    from cpg_actor.machine import cpu_model, load_average, usable_cores

    available = sorted(os.sched_getaffinity(0))
    if any(c != "all" and not (c.isdigit() and int(c) > 0) for c in args.cores):
        parser.error(f"--cores takes positive integers or 'all', got {' '.join(args.cores)}")
    counts = sorted({len(available) if c == "all" else int(c) for c in args.cores})
    rows = []
    for cores in counts:
        if cores > len(available):
            print(f"skipped: {cores} cores (this machine has {len(available)})")
            continue
        for num_envs in args.num_envs:
            pinned = available[:cores]
            command = [sys.executable, __file__, "--agent", args.agent, "--iterations",
                       str(args.iterations), "--child", str(cores), str(num_envs)]  # fmt: skip
            out = subprocess.run(
                command,
                preexec_fn=lambda pinned=pinned: os.sched_setaffinity(0, pinned),
                capture_output=True,
                text=True,
                check=True,
            ).stdout
            result = json.loads(out.strip().splitlines()[-1])
            rows.append(result)
            print(
                f"{result['cores']} cores, {num_envs} envs: {result['SPS']:,.0f} SPS, "
                f"ceiling {result['ceiling']:,.0f}",
                flush=True,
            )
    lines = [
        "# Training throughput against CPU cores",
        "",
        f"Measured {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC with "
        f"`python benchmarks/train_scaling.py --cores {' '.join(args.cores)} --num-envs "
        f"{' '.join(map(str, args.num_envs))} --agent {args.agent}` on {cpu_model()}, "
        f"{usable_cores()} usable cores (load {load_average()}). Throughput preset "
        "(compiled updates), torch threads = simulator cores = the pinned cores.",
        "",
        "| cores | envs | training SPS | ceiling (`mujoco.rollout`) | of ceiling | "
        "collection us/step | update us/sample |",
        "| ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in rows:
        lines.append(
            f"| {r['cores']} | {r['num_envs']} | {r['SPS']:,.0f} | {r['ceiling']:,.0f} | "
            f"{r['SPS'] / r['ceiling']:.0%} | {r['collect_us']:.1f} | {r['update_us']:.1f} |"
        )
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
