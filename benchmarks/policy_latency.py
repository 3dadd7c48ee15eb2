"""Per-step latency of a deployed policy on one core: the PyTorch `Policy`, the TorchScript and
the ONNX export (onnxruntime), one robot per call, next to a reference measured in the same
run (`torch.nn.Linear(8, 64)` forward, the smallest thing a policy does).

    python benchmarks/policy_latency.py [--steps 5000] [--agents cpg-actor mlp]
        [--output benchmarks/results/policy_latency.md]

A robot runs its control loop at 100 to 400 Hz (2.5 to 10 ms per step); the aim is a p99 well
under 1 ms.
"""

from __future__ import annotations

import argparse
import datetime
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from cpg_actor.config import TrainConfig
from cpg_actor.deploy import load_policy
from cpg_actor.deploy.export import export_policy
from cpg_actor.machine import cpu_model, load_average
from cpg_actor.ppo import PPOConfig
from cpg_actor.training.runner import Runner


def latencies(step, steps: int) -> np.ndarray:
    """Microseconds per call, after 200 warm-up calls."""
    for _ in range(200):
        step()
    times = np.empty(steps)
    for i in range(steps):
        start = time.perf_counter_ns()
        step()
        times[i] = (time.perf_counter_ns() - start) / 1e3
    return times


def measure(agent: str, steps: int, folder: Path) -> dict[str, np.ndarray]:
    config = TrainConfig(
        agent=agent,
        num_envs=2,
        total_steps=32,
        ppo=PPOConfig(num_steps=8, num_epochs=1, num_minibatches=2),
        eval_interval=0,
    )
    runner = Runner(config, run_dir=folder / agent, tensorboard=False)
    runner.learn()
    runner.close()
    policy = load_policy(folder / agent)
    policy.reset(1)
    obs = np.zeros((1, 8), dtype=np.float32)
    obs[0, :2] = (0.4, -0.8)
    results = {"PyTorch Policy.act": latencies(lambda: policy.act(obs), steps)}

    script = torch.jit.load(str(export_policy(policy, folder / f"{agent}.pt", "torchscript")))
    state = torch.as_tensor(policy.agent.initial_state(1))
    obs_t = torch.as_tensor(obs)
    results["TorchScript"] = latencies(lambda: script(obs_t, state), steps)

    import onnxruntime as ort

    options = ort.SessionOptions()
    options.intra_op_num_threads = options.inter_op_num_threads = 1
    path = export_policy(policy, folder / f"{agent}.onnx", "onnx")
    session = ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
    feed = {"observation": obs, "state": state.numpy()}
    results["ONNX Runtime"] = latencies(lambda: session.run(None, feed), steps)
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--agents", nargs="+", default=["cpg-actor", "mlp"])
    parser.add_argument("--output", default="benchmarks/results/policy_latency.md")
    args = parser.parse_args()
    torch.set_num_threads(1)
    linear, x = torch.nn.Linear(8, 64), torch.zeros(1, 8)
    with torch.no_grad():
        reference = np.median(latencies(lambda: linear(x), args.steps))
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for agent in args.agents:
            for name, times in measure(agent, args.steps, Path(folder)).items():
                p50, p99 = np.percentile(times, [50, 99])
                rows.append(
                    f"| {agent} | {name} | {p50:.0f} | {p99:.0f} | {times.max():.0f} | "
                    f"{p50 / reference:.1f} |"
                )
                print(rows[-1])
    lines = [
        "# Policy latency (one robot, one core)",
        "",
        f"Measured {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC with "
        f"`python benchmarks/policy_latency.py --steps {args.steps} --agents "
        f"{' '.join(args.agents)}` on {cpu_model()} (load {load_average()}), torch "
        f"{torch.__version__}, 1 torch thread, onnxruntime 1 thread.",
        "",
        f"Reference in the same run: `torch.nn.Linear(8, 64)` forward, median "
        f"**{reference:.1f} us**.",
        "",
        "| agent | runtime | p50 (us) | p99 (us) | max (us) | p50 / reference |",
        "| --- | --- | ---: | ---: | ---: | ---: |",
        *rows,
        "",
        "One call is a whole control step: observation normaliser, networks, CPG step (for the",
        "CPG-Actor) and action clip; `Policy.act` also converts numpy to torch and back.",
        "",
    ]
    Path(args.output).write_text("\n".join(lines))
    print(f"written {args.output}")


if __name__ == "__main__":
    main()
