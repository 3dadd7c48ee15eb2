"""tanh on this CPU: ``torch.tanh`` against the form the agents use, ``2 sigmoid(2x) - 1``
(``cpg_actor.agents.base.tanh``), with ``torch.sigmoid`` as the reference, measured in the
same run. Forward alone and forward + backward through a 64 x 64 layer, eager and compiled,
at the batch sizes of a rollout step (256) and of a PPO minibatch (2,048).

    python benchmarks/activation.py [--output benchmarks/results/activation.md]
"""

from __future__ import annotations

import argparse

import torch
from torch.utils import benchmark

from bench_report import measured, write
from cpg_actor.agents.base import tanh
from cpg_actor.machine import cpu_model, load_average


def layer_loss(activation):
    def loss(x: torch.Tensor, weight: torch.Tensor) -> torch.Tensor:
        return activation(activation(x @ weight) @ weight).sum()

    return loss


def median_us(stmt: str, min_run_time: float = 0.3, **env) -> float:
    timer = benchmark.Timer(stmt=stmt, globals=env, num_threads=1)
    return timer.blocked_autorange(min_run_time=min_run_time).median * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch-sizes", type=int, nargs="+", default=[256, 2048])
    parser.add_argument("--min-run-time", type=float, default=0.3, help="seconds per measurement")
    parser.add_argument("--output", default="benchmarks/results/activation.md")
    args = parser.parse_args()
    torch.manual_seed(0)
    weight = (torch.randn(64, 64) / 8).requires_grad_()
    forms = {"torch.tanh": torch.tanh, "2 sigmoid(2x) - 1": tanh}
    rows = []
    time = args.min_run_time
    for batch in args.batch_sizes:
        x = torch.randn(batch, 64)
        sigmoid = median_us("torch.sigmoid(x)", time, x=x)
        for name, fn in forms.items():
            alone = median_us("fn(x)", time, fn=fn, x=x)
            eager = median_us("loss(x, w).backward()", time, loss=layer_loss(fn), x=x, w=weight)
            compiled_loss = torch.compile(layer_loss(fn), dynamic=False)
            compiled_loss(x, weight).backward()  # compile outside the timing
            compiled = median_us("loss(x, w).backward()", time, loss=compiled_loss, x=x, w=weight)
            rows.append((batch, name, alone, alone / sigmoid, eager, compiled))
    difference = (torch.tanh(x) - tanh(x)).abs().max().item()
    lines = [
        "# tanh on the CPU",
        "",
        measured(
            f"python benchmarks/activation.py --batch-sizes {' '.join(map(str, args.batch_sizes))}"
        )
        + ".",  # fmt: skip
        "",
        f"Machine: {cpu_model()}, 1 torch thread (load {load_average()}), torch "
        f"{torch.__version__}, float32; medians of `torch.utils.benchmark` blocked runs.",
        "",
        "| batch x 64 | form | alone (us) | alone / sigmoid | 2 layers fwd+bwd eager (us) "
        "| 2 layers fwd+bwd compiled (us) |",
        "| ---: | --- | ---: | ---: | ---: | ---: |",
    ]
    lines += [
        f"| {b:,} | `{name}` | {alone:.1f} | {ratio:.1f} | {eager:.0f} | {compiled:.0f} |"
        for b, name, alone, ratio, eager, compiled in rows
    ]
    lines += [
        "",
        f"Largest difference between the two forms on N(0, 1) inputs: {difference:.1e}.",
        "`alone / sigmoid`: the time of the form over `torch.sigmoid` on the same tensor. "
        "`2 layers`: `act(act(x @ W) @ W).sum()` and its backward, the shape of the agents' "
        "MLPs. The agents use the second form (`cpg_actor.agents.base.tanh`).",
        "",
    ]
    write(args.output, lines)


if __name__ == "__main__":
    main()
