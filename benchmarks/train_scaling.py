"""Training throughput against the number of CPU cores: does training get faster with cores?

    python benchmarks/train_scaling.py [--cores 2 8 all] [--num-envs 64 1024]
        [--agent cpg-actor] [--output benchmarks/results/train_scaling.md]

For each core count C and number of envs N, a subprocess pinned to C cores
(``os.sched_setaffinity``) trains the throughput preset with N envs and the run's own thread
settings, as a user gets them: the simulator's threads follow the usable cores (at least 8
robots per thread), the rollout's policy runs on one torch thread (``torch_threads``) and the
update on every pinned core for minibatches of at least 1,024 samples (``update_threads``).
It reports the training SPS after a warm-up iteration, next to the physics ceiling of the
same motion (``mujoco.rollout`` replaying the control steps the training visited, on the same
C cores: ``train_throughput.py``), both measured in the same subprocess. The table is
rewritten after each row, so a run cut short keeps the rows it measured. Core counts above
the machine's are skipped.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def measure(agent: str, num_envs: int, iterations: int) -> dict:
    """In this (pinned) process: training SPS and the physics ceiling for ``num_envs``."""
    sys.path.insert(0, str(HERE))
    from cpg_actor.machine import usable_cores
    from train_throughput import measure as train_measure

    # the run's defaults: torch_threads 1 for the rollout, update_threads automatic
    result = train_measure(
        agent, "throughput", iterations, compile=True, num_envs=num_envs, ceiling=True
    )
    result["cores"] = usable_cores()
    return result


def table(args: argparse.Namespace, rows: list[dict]) -> str:
    """The Markdown table of the rows measured so far."""
    from bench_report import measured
    from cpg_actor.machine import cpu_model, load_average, usable_cores

    command = (
        f"python benchmarks/train_scaling.py --cores {' '.join(args.cores)} --num-envs "
        f"{' '.join(map(str, args.num_envs))} --agent {args.agent}"
    )
    lines = [
        "# Training throughput against CPU cores",
        "",
        f"{measured(command)} on {cpu_model()}, "
        f"{usable_cores()} usable cores (load {load_average()}). Throughput preset "
        "(compiled), the run's thread settings: the simulator on the pinned cores, the "
        "rollout's policy on 1 torch thread, the update on every pinned core for minibatches "
        "of at least 1,024 samples (128 envs and more), else on 1 thread.",
        "",
        "| cores | envs | training SPS | ceiling (`mujoco.rollout`) | of ceiling | of ceiling, "
        "paired per iteration | of MuJoCo's pool, paired | collection us/step | update "
        "us/sample |",
        "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in rows:
        paired = f"{r['paired_share']:.0%}" if "paired_share" in r else "-"
        pool = f"{r['paired_share_pool']:.0%}" if "paired_share_pool" in r else "-"
        lines.append(
            f"| {r['cores']} | {r['num_envs']} | {r['SPS']:,.0f} | {r['ceiling']:,.0f} | "
            f"{r['SPS'] / r['ceiling']:.0%} | {paired} | {pool} | {r['collect_us']:.1f} | "
            f"{r['update_us']:.1f} |"
        )
    lines += [
        "",
        "Of ceiling: the training SPS over the ceiling replayed after the row; paired per "
        "iteration: the median over the timed iterations of each one's SPS over the ceiling of "
        "its own motion replayed right after it (`train_throughput.py`); of MuJoCo's pool: "
        "the same against `mujoco.rollout`'s own thread pool alone (the ceiling takes the "
        "faster of it and the env's `ThreadedRollout`).",
    ]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cores", nargs="+", default=["2", "8", "all"])
    parser.add_argument("--num-envs", nargs="+", type=int, default=[64, 1024])
    parser.add_argument("--agent", default="cpg-actor")
    parser.add_argument("--iterations", type=int, default=3)
    parser.add_argument("--output", default=str(HERE / "results" / "train_scaling.md"))
    parser.add_argument("--child", nargs=2, type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.iterations < 1:
        parser.error(f"--iterations must be >= 1, got {args.iterations}")
    if args.child:  # one measurement, printed as JSON
        print(json.dumps(measure(args.agent, args.child[1], args.iterations)))
        return

    available = sorted(os.sched_getaffinity(0))
    if any(c != "all" and not (c.isdigit() and int(c) > 0) for c in args.cores):
        parser.error(f"--cores takes positive integers or 'all', got {' '.join(args.cores)}")
    counts = sorted({len(available) if c == "all" else int(c) for c in args.cores})
    output = Path(args.output)
    output.parent.mkdir(parents=True, exist_ok=True)
    rows: list[dict] = []
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
            output.write_text(table(args, rows))  # a run cut short keeps its rows
            print(
                f"{result['cores']} cores, {num_envs} envs: {result['SPS']:,.0f} SPS, "
                f"ceiling {result['ceiling']:,.0f}",
                flush=True,
            )
    print(table(args, rows), end="")


if __name__ == "__main__":
    main()
