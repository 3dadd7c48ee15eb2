"""An exported quadruped policy on a model it was not trained on: its forward-speed tracking
on its own model next to another faithful model of the same robot.

    cpg-actor train --robot go1 --total-steps 500k --seed 0 --run-dir runs/go1
    cpg-actor export runs/go1
    python benchmarks/other_model.py runs/go1/export/policy.onnx [--commands 0.3,0.5,0.8]
        [--seeds 1000,1001,1002] [--mjcf PATH] [--steps N]
        [--output benchmarks/results/go1_other_model.md]

Everything runs through ``examples/deploy_onnx.py`` (numpy, onnxruntime and mujoco: what a
user who moves the policy to their own simulator runs), one episode per (model, command,
start seed), the command held for the whole episode (20 s). Three models:

* ``own``: the MJCF the export wrote next to the policy, its ``dcmotor`` actuators running
  the actuator law inside MuJoCo (the model the policy trained on);
* ``own, law as torques``: the same file through ``--mjcf``, the law applied as joint torques
  by the example, as on any other model (separates the way the law is applied from the model);
* ``other``: ``--mjcf`` (default the Go1 variant of :mod:`cpg_actor.robots.go1.variant`:
  mjlab's passive dynamics and contact);
* with ``--ablation``, ``only TERM``: the Go1's own model with one of the variant's
  differences alone (:data:`cpg_actor.robots.go1.variant.TERMS`), written to a temporary file:
  which difference moves the tracking.

Speed error: the mean over the episode of |forward speed - command| (the forward speed is the
base-frame x velocity at the IMU site, as the env's ``speed_error``), then the mean over the
start seeds; a fall ends the episode (and counts).
"""

from __future__ import annotations

import argparse
import json
import runpy
import sys
import tempfile
from pathlib import Path

import mujoco
import numpy as np
import onnxruntime as ort

from bench_report import measured, write
from cpg_actor.machine import cpu_model, load_average, usable_cores

HERE = Path(__file__).resolve().parent
EXAMPLE = HERE.parent / "examples" / "deploy_onnx.py"
OUTPUT = "benchmarks/results/go1_other_model.md"


def episode(example: dict, policy, mjcf: Path, other: bool, command: float, seed: int,
            steps: int | None) -> dict:  # fmt: skip
    """One episode of the example: its speed error, mean forward speed and whether it fell."""
    sim = example["Simulation"](policy.meta, mjcf, other=other)
    sim.fixed_command = [command, 0.0, 0.0]
    _, length, ended = example["run_episode"](policy, sim, seed, steps)
    speeds = np.asarray(sim.forward_speeds)
    return {"speed_error": round(float(np.abs(speeds - command).mean()), 5),
            "forward_speed": round(float(speeds.mean()), 5), "fell": ended == "terminated",
            "steps": int(length)}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    from cpg_actor.robots.go1.variant import TERMS, VARIANT_PATH, variant_mjcf

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("policy", type=Path, help="an ONNX file from cpg-actor export")
    parser.add_argument("--mjcf", type=Path, default=VARIANT_PATH, help="the other model")
    parser.add_argument("--commands", default="0.3,0.5,0.8", help="forward commands, m/s")
    parser.add_argument("--seeds", default="1000,1001,1002", help="the episodes' start seeds")
    parser.add_argument("--steps", type=int, default=None, help="cap each episode (tests)")
    parser.add_argument("--ablation", action="store_true",
                        help="also each of the Go1 variant's differences alone")  # fmt: skip
    parser.add_argument("--output", default=OUTPUT)
    args = parser.parse_args(argv)
    example = runpy.run_path(str(EXAMPLE))
    policy = example["Policy"](example["policy_file"](args.policy))
    own = args.policy.with_name(policy.meta["mjcf_file"])
    commands = [float(c) for c in args.commands.split(",")]
    seeds = [int(s) for s in args.seeds.split(",")]
    models = {"own": (own, False), "own, law as torques": (own, True),
              "other": (args.mjcf, True)}  # fmt: skip
    scratch = tempfile.TemporaryDirectory()
    if args.ablation:
        for term in TERMS:
            path = Path(scratch.name) / f"go1_only_{term}.xml"
            path.write_text(variant_mjcf(only=term))
            models[f"only {term}"] = (path, True)
    results: dict[str, dict[str, list[dict]]] = {}
    for name, (mjcf, other) in models.items():
        for command in commands:
            runs = [episode(example, policy, mjcf, other, command, seed, args.steps)
                    for seed in seeds]  # fmt: skip
            results.setdefault(name, {})[f"{command:g}"] = runs
            error = np.mean([r["speed_error"] for r in runs])
            print(f"{name} at {command:g} m/s: speed error {error:.3f} m/s", file=sys.stderr)
    argv_text = " ".join(argv if argv is not None else sys.argv[1:])
    scratch.cleanup()
    lines = [
        f"# {policy.meta['agent']} on {policy.meta['robot_model']}: its own model and another",
        "",
        f"{measured(f'python benchmarks/other_model.py {argv_text}')}, on {cpu_model()}, "
        f"{usable_cores()} usable cores (load {load_average()}), onnxruntime "
        f"{ort.__version__}, mujoco {mujoco.__version__}.",
        "",
        f"Policy: `{args.policy}` ({policy.meta['agent']}, {policy.meta['robot_model']}). "
        f"Other model: `{args.mjcf.name}`. One episode per start seed "
        f"({', '.join(map(str, seeds))}), "
        "the forward command held for the episode; speed error: the mean over the episode of "
        "|forward speed - command|, then over the seeds (m/s); falls: episodes ended by a fall.",
        "",
        "| model | " + " | ".join(f"{c:g} m/s: speed error (speed), falls" for c in commands)
        + " |",
        "| --- | " + " | ".join("---:" for _ in commands) + " |",
    ]  # fmt: skip
    for name in models:
        cells = []
        for command in commands:
            runs = results[name][f"{command:g}"]
            error = np.mean([r["speed_error"] for r in runs])
            speed = np.mean([r["forward_speed"] for r in runs])
            cells.append(f"{error:.3f} ({speed:.3f}), {sum(r['fell'] for r in runs)} / "
                         f"{len(runs)}")  # fmt: skip
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    lines += ["", "Per episode (JSON):", "", "```json", json.dumps(results), "```", ""]
    write(args.output, lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
