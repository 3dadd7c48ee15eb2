"""Time one CPG step (the hopper preset) on CPU, forward and forward+backward.

For each batch size the script measures, with ``torch.utils.benchmark``:

* ``CPG fwd``: one step under ``torch.no_grad()`` with input validation on (the default), as
  during a rollout;
* ``CPG fwd (unchecked)``: the same with ``check_inputs=False``;
* ``CPG fwd+bwd``: one step with gradients to V, xi and kappa and ``backward()`` of a scalar
  loss on x and x_dot, as in a PPO update that replays one step from the stored state;
* the reference, ``torch.nn.Linear(8, 64)``, forward and forward+backward at the same batch,
  measured in the same run, and the CPG's time as a multiple of it.

Run: ``python benchmarks/cpg_step.py`` (writes ``benchmarks/results/cpg_step.md`` and prints it).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
from pathlib import Path

import torch
from torch.utils import benchmark

from cpg_actor.cpg import CPGState
from cpg_actor.machine import cpu_model, load_average
from cpg_actor.robots.hopper.cpg import hopper_cpg

DEFAULT_OUT = Path(__file__).resolve().parent / "results" / "cpg_step.md"
BATCH_SIZES = (1, 16, 256, 1024, 4096)
DT = 0.01


def machine_description(threads: int) -> list[str]:
    load = load_average()
    return [
        f"- CPU: {cpu_model()}",
        f"- logical cores: {os.cpu_count()}",
        f"- torch {torch.__version__}, {threads} intra-op thread(s), float32",
        f"- Python {platform.python_version()} on {platform.system()} {platform.release()}",
        f"- load average when the run started (1, 5, 15 min): {load}",
    ]


def measure(fn, threads: int, min_run_time: float) -> float:
    """Median seconds per call."""
    fn()  # warm-up (allocations, lazy initialisation)
    timer = benchmark.Timer(stmt="fn()", globals={"fn": fn}, num_threads=threads)
    return timer.blocked_autorange(min_run_time=min_run_time).median


def random_state(batch: int, n: int) -> CPGState:
    g = torch.Generator().manual_seed(0)
    return CPGState(
        phase=torch.rand(batch, n, generator=g) * 6.28,
        phase_velocity=torch.full((batch, n), 12.5),
        amplitude=torch.rand(batch, n, generator=g) * 0.3,
        amplitude_velocity=torch.randn(batch, n, generator=g),
        amplitude_acceleration=torch.randn(batch, n, generator=g),
    )


def bench_batch(batch: int, threads: int, min_run_time: float) -> dict[str, float]:
    checked, unchecked = hopper_cpg(DT), hopper_cpg(DT, check_inputs=False)
    n = checked.num_oscillators
    state = random_state(batch, n)
    g = torch.Generator().manual_seed(1)
    xi, kappa = torch.randn(batch, n, generator=g), torch.randn(batch, n, generator=g)
    drive = 0.0
    linear = torch.nn.Linear(8, 64)
    features = torch.randn(batch, 8, generator=g)

    def cpg_forward(net=checked):
        with torch.no_grad():
            return net(state, drive, xi, kappa)

    xi_grad, kappa_grad = xi.clone().requires_grad_(True), kappa.clone().requires_grad_(True)

    def cpg_forward_backward():
        checked.zero_grad(set_to_none=True)
        xi_grad.grad = kappa_grad.grad = None
        out, _ = checked(state, drive, xi_grad, kappa_grad)
        (out.position.sum() + out.velocity.sum()).backward()

    def linear_forward():
        with torch.no_grad():
            return linear(features)

    def linear_forward_backward():
        linear.zero_grad(set_to_none=True)
        linear(features).sum().backward()

    return {
        "cpg_fwd": measure(cpg_forward, threads, min_run_time),
        "cpg_fwd_unchecked": measure(lambda: cpg_forward(unchecked), threads, min_run_time),
        "cpg_fwd_bwd": measure(cpg_forward_backward, threads, min_run_time),
        "lin_fwd": measure(linear_forward, threads, min_run_time),
        "lin_fwd_bwd": measure(linear_forward_backward, threads, min_run_time),
    }


def render(results: dict[int, dict[str, float]], threads: int, min_run_time: float) -> str:
    us = 1e6
    lines = [
        "# CPG step benchmark",
        "",
        f"`python benchmarks/cpg_step.py`, {datetime.date.today().isoformat()}: one step of the "
        "hopper CPG (2 oscillators, M = 8, "
        f"dt = {DT} s), median of `torch.utils.benchmark` blocked runs "
        f"(min_run_time {min_run_time} s each). Reference: `torch.nn.Linear(8, 64)` at the same "
        "batch, measured in the same run; *ratio* = CPG time / reference time.",
        "",
        *machine_description(threads),
        "",
        "| batch | CPG fwd (us) | fwd us/sample | CPG fwd unchecked (us) | CPG fwd+bwd (us) "
        "| fwd+bwd us/sample | Linear fwd (us) | Linear fwd+bwd (us) | fwd ratio "
        "| fwd+bwd ratio |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for batch, r in results.items():
        lines.append(
            f"| {batch} | {r['cpg_fwd'] * us:.1f} | {r['cpg_fwd'] * us / batch:.3f} "
            f"| {r['cpg_fwd_unchecked'] * us:.1f} | {r['cpg_fwd_bwd'] * us:.1f} "
            f"| {r['cpg_fwd_bwd'] * us / batch:.3f} | {r['lin_fwd'] * us:.1f} "
            f"| {r['lin_fwd_bwd'] * us:.1f} | {r['cpg_fwd'] / r['lin_fwd']:.1f} "
            f"| {r['cpg_fwd_bwd'] / r['lin_fwd_bwd']:.1f} |"
        )
    lines += [
        "",
        "*fwd*: `torch.no_grad()`, input validation on (the default; it checks shapes, dtypes "
        "and finiteness, one host sync on CUDA). *unchecked*: `check_inputs=False`. "
        "*fwd+bwd*: gradients to V, xi and kappa, `backward()` of `x.sum() + x_dot.sum()`, "
        "grads reset to None each call.",
        "",
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch-sizes", type=int, nargs="+", default=list(BATCH_SIZES))
    parser.add_argument("--threads", type=int, default=torch.get_num_threads())
    parser.add_argument("--min-run-time", type=float, default=0.3, help="seconds per measurement")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="Markdown file to write")
    args = parser.parse_args(argv)
    if args.threads < 1 or args.min_run_time <= 0 or min(args.batch_sizes) < 1:
        parser.error("--threads, --min-run-time and --batch-sizes must be positive")
    torch.set_num_threads(args.threads)
    results = {}
    for batch in args.batch_sizes:
        results[batch] = bench_batch(batch, args.threads, args.min_run_time)
        print(f"batch {batch}: done", file=sys.stderr)
    report = render(results, args.threads, args.min_run_time)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    temporary = args.out.with_name(args.out.name + ".tmp")
    temporary.write_text(report, encoding="utf-8")
    os.replace(temporary, args.out)
    print(report)
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
