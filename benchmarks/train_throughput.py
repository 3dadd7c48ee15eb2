"""End-to-end PPO training throughput per agent and preset: control steps per second, the
collection cost per control step, the PPO update cost per sample, next to the raw physics
ceiling of the same motion, in the same run: ``mujoco.rollout`` on the project's MJCF
replaying the control steps the row's training visited (:class:`env_throughput.ReplayCeiling`:
their recorded states, the torques the env applied held constant, the actuators off).

    python benchmarks/train_throughput.py [--presets paper throughput] [--agents mlp cpg-actor]
        [--iterations 4] [--reference-src OLD/src] [--output benchmarks/results/train_throughput.md]

``--reference-src DIR`` measures the same settings, in the same run, with the ``cpg_actor``
package found in DIR (e.g. a ``git worktree`` of an older commit), in a subprocess, and reports
the ratios: how much faster (or slower) the code under test is than that reference, row by
row (same preset, agent and compile setting; the reference tree must know the presets).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

from cpg_actor.machine import (
    brief_openmp_spinning,
    cpu_model,
    cpu_times,
    load_average,
    stolen_share,
    usable_cores,
)

brief_openmp_spinning(os.environ)  # as the cpg-actor command runs (before torch loads)

import torch  # noqa: E402

from cpg_actor.config import TrainConfig, apply_dict  # noqa: E402
from cpg_actor.config.presets import preset_values  # noqa: E402
from cpg_actor.training.runner import Runner  # noqa: E402

AGENTS = ("mlp", "cpg-actor", "cpg-actor-open-loop")


def make_config(
    agent: str,
    preset: str,
    compile: bool,
    device: str = "cpu",
    num_envs: int | None = None,
    torch_threads: int = 1,
    update_threads: int | None = None,
) -> TrainConfig:
    config = TrainConfig(agent=agent, torch_threads=torch_threads)
    if update_threads is not None:  # (a reference tree may predate the field)
        config.update_threads = update_threads
    apply_dict(config, preset_values(preset), "")
    config.eval_interval = 0
    config.ppo.compile = compile  # the presets compile; rows say which
    if device != "cpu":
        config.device = device
    if num_envs is not None:
        config.num_envs = num_envs
    return config


def measure(
    agent: str,
    preset: str,
    iterations: int,
    compile: bool = False,
    device: str = "cpu",
    num_envs: int | None = None,
    torch_threads: int = 1,
    update_threads: int | None = None,
    ceiling: bool = False,
) -> dict[str, float]:
    """One warm-up iteration (and the compile), then ``iterations`` timed ones; with
    ``ceiling``, also the physics ceiling of the timed iterations' motion (``ceiling``), and
    ``paired_share``: the median over the timed iterations of each one's control steps per
    second over the ceiling of its own motion, replayed right after it, the better of two
    replays as for ``ceiling`` (within a second or two, so that a machine whose speed drifts
    slows both alike; the replays are not timed as training). ``stolen`` and
    ``ceiling_stolen``: the share of the machine's CPU time its hypervisor took during the
    timed iterations and during the ceiling (:func:`stolen_share`)."""
    config = make_config(agent, preset, compile, device, num_envs, torch_threads, update_threads)
    config.total_steps = (iterations + 1) * config.steps_per_iteration
    runner = Runner(config, run_dir=None, tensorboard=False)
    collect = update = simulation = stolen_cpu = 0.0
    recorder = None
    shares: list[float] = []  # each timed iteration's SPS over its own motion's ceiling
    pool_shares: list[float] = []  # the same over MuJoCo's own pool stepping that motion
    try:
        runner.start_episodes()
        for i in range(iterations + 1):
            if i == 1 and ceiling:
                recorder = record_motion(runner)
            recorded = recorder.steps if recorder is not None else 0
            cpu_start = cpu_times()
            start = time.perf_counter()
            info = runner.collect()
            collected = time.perf_counter()
            if hasattr(runner, "update"):  # on the run's update threads
                runner.update()
            else:  # a reference tree from before Runner.update
                runner.ppo.update(runner.storage)
            end = time.perf_counter()
            if i > 0:
                collect += collected - start
                update += end - collected
                simulation += info["simulation_time"]
                stolen_cpu += stolen_share(cpu_start, cpu_times()) * (end - start)
                if recorder is not None:
                    motion = recorder.slice(recorded)
                    rates = replay_ceiling(recorder, motion)  # best of 2, as below
                    sps = config.steps_per_iteration / (end - start)
                    shares.append(sps / rates["ceiling"])
                    pool_shares.append(sps / rates["pool"])
        motion = recorder.stop() if recorder is not None else None
    finally:
        runner.close()
    samples = iterations * config.steps_per_iteration
    extra = {}
    if motion is not None:
        cpu_end = cpu_times()
        rates = replay_ceiling(recorder, motion)
        extra["ceiling"], extra["ceiling_pool"] = rates["ceiling"], rates["pool"]
        extra["ceiling_stolen"] = stolen_share(cpu_end, cpu_times())
        extra["paired_share"] = statistics.median(shares)
        extra["paired_share_pool"] = statistics.median(pool_shares)
    return {
        **extra,
        "stolen": stolen_cpu / (collect + update),
        "num_envs": config.num_envs,
        "SPS": samples / (collect + update),
        "collect_us": 1e6 * collect / samples,
        "simulation_us": 1e6 * simulation / samples,
        # the rollout outside env.step: policy, normalisers, storage, episode bookkeeping, GAE
        "outside_us": 1e6 * (collect - simulation) / samples,
        "update_us": 1e6 * update / samples,
    }


def _benchmarks():
    here = str(Path(__file__).parent)
    if here not in sys.path:
        sys.path.insert(0, here)
    import env_throughput

    return env_throughput


def mujoco_backend(runner: Runner):
    """The run's MuJoCo backend (below any env wrapper, e.g. Cho et al.'s CPG), or None."""
    env = runner.env.unwrapped
    while not hasattr(env, "sim") and hasattr(env, "env"):
        env = env.env
    backend = getattr(getattr(env, "sim", None), "backend", None)
    return backend if getattr(backend, "name", None) == "mujoco" else None


def record_motion(runner: Runner):
    """A :class:`env_throughput.MotionRecorder` on the run's MuJoCo backend (None if other)."""
    backend = mujoco_backend(runner)
    return None if backend is None else _benchmarks().MotionRecorder(backend)


def replay_ceiling(recorder, motion: tuple, repeats: int = 2) -> dict[str, float]:
    """Control steps per second of ``mujoco.rollout`` replaying the ``motion`` that
    ``recorder`` recorded (:class:`env_throughput.ReplayCeiling`, on as many threads as the
    backend), best of ``repeats``: ``ceiling``, the faster of MuJoCo's thread pool and the
    env's ``ThreadedRollout``, and ``pool``, MuJoCo's thread pool alone (``mujoco.rollout``
    as it comes, the issue's ceiling)."""
    backend = recorder.backend
    ceiling = _benchmarks().ReplayCeiling(
        backend.model, *motion, recorder.substeps, backend.num_threads
    )
    try:
        rates = [ceiling.rollout_rates() for _ in range(repeats)]
    finally:
        ceiling.close()
    pool = max(r["pool"] for r in rates)
    return {"ceiling": max(max(r.values()) for r in rates), "pool": pool}


def reference(
    src: str, presets: list[str], agents: list[str], iterations: int, compile: bool
) -> dict:
    """The same measurements with the package in ``src``, in a subprocess."""
    arguments = [__file__, "--json", "--iterations", str(iterations)]
    arguments += ["--presets", *presets, "--agents", *agents] + (["--compile"] if compile else [])
    from bench_report import json_from_tree

    return json_from_tree(src, arguments)


def measure_all(args: argparse.Namespace) -> dict[str, dict[str, float]]:
    """Every row of the table once: presets x agents (eager, compiled, update on 1 thread)."""
    extra = {"device": args.device, "num_envs": args.num_envs, "ceiling": not args.json}
    variants = [("", {})]
    if args.compile:
        variants.append((" + compile", {"compile": True}))
    if args.update_threads_ab:
        variants.append((" + compile, update on 1 thread", {"compile": True, "update_threads": 1}))
    return {
        f"{preset}{suffix}/{agent}": measure(agent, preset, args.iterations, **options, **extra)
        for suffix, options in variants
        for preset in args.presets
        for agent in args.agents
    }


def median_of(runs: list[dict[str, dict[str, float]]]) -> dict[str, dict[str, float]]:
    """The median of each figure of each row over repeated measurements."""
    return {
        key: {
            field: statistics.median(run[key][field] for run in runs)
            if field != "num_envs"
            else runs[0][key][field]
            for field in runs[0][key]
        }
        for key in runs[0]
    }


def paired_speedups(runs: list[dict], ref_runs: list[dict], key: str, field: str) -> list[float]:
    """The speed-up of ``field`` (SPS: code over reference; a cost: reference over code) in
    each repeat, the two measured back to back: a slow spell of a shared machine hits both."""
    pairs = [(run[key][field], ref[key][field]) for run, ref in zip(runs, ref_runs, strict=True)]
    return [new / old if field == "SPS" else old / new for new, old in pairs]


def fmt_share(share: float, repeats: list[float]) -> str:
    """A share of the ceiling and, over several repeats, their lowest and highest in brackets."""
    text = f"{share:.0%}"
    if len(repeats) > 1:
        text += f" ({min(repeats):.0%}-{max(repeats):.0%})"
    return text


def fmt_ceiling(row: dict[str, float], repeats: list[dict[str, float]] = ()) -> str:
    """The row's ceiling, its share of it, its paired share and its paired share of
    MuJoCo's own pool (:func:`measure`), each share with the lowest and highest of
    ``repeats`` (the row's measurements) in brackets; dashes without a MuJoCo ceiling (e.g.
    MJX)."""
    if "ceiling" not in row:
        return "- | - | - | -"
    share = fmt_share(row["SPS"] / row["ceiling"], [r["SPS"] / r["ceiling"] for r in repeats])
    paired = fmt_share(row["paired_share"], [r["paired_share"] for r in repeats])
    pool = fmt_share(row["paired_share_pool"], [r["paired_share_pool"] for r in repeats])
    return f"{row['ceiling']:,.0f} | {share} | {paired} | {pool}"


def fmt_stolen(row: dict[str, float]) -> str:
    """The hypervisor's share of the CPU time during the training and its ceiling."""
    shares = [row.get(key, float("nan")) for key in ("stolen", "ceiling_stolen")]
    return " / ".join("-" if math.isnan(share) else f"{share:.0%}" for share in shares)


def fmt_speedup(ratios: list[float]) -> str:
    """The median speed-up and, over several repeats, the range of the paired ones."""
    if len(ratios) < 2:
        return f"{ratios[0]:.2f}x"
    return f"{statistics.median(ratios):.2f}x ({min(ratios):.2f}-{max(ratios):.2f})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="+", default=["paper", "throughput"])
    parser.add_argument("--agents", nargs="+", default=list(AGENTS))
    parser.add_argument("--iterations", type=int, default=4)
    parser.add_argument("--compile", action="store_true", help="also measure with ppo.compile=true")
    parser.add_argument("--device", default="cpu", help="cpu (default) or cuda")
    parser.add_argument("--num-envs", type=int, default=None, help="override the preset's")
    parser.add_argument("--reference-src", help="a src/ folder holding the reference cpg_actor")
    parser.add_argument(
        "--update-threads-ab",
        action="store_true",
        help="also the compiled rows with the PPO update on 1 thread (update_threads=1)",
    )
    parser.add_argument(
        "--repeats",
        type=int,
        default=1,
        help="measure every row (and the reference and ceiling) N times, interleaved; medians",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON line, write nothing")
    parser.add_argument("--output", default="benchmarks/results/train_throughput.md")
    args = parser.parse_args()
    torch.set_num_threads(1)

    if args.repeats < 1 or args.iterations < 1:
        parser.error(
            f"--repeats and --iterations must be >= 1, got {args.repeats} and {args.iterations}"
        )
    runs, ref_runs = [], []
    for _ in range(args.repeats):  # interleaved: a busy neighbour affects all alike
        runs.append(measure_all(args))
        if args.json:
            continue
        if args.reference_src:
            ref_runs.append(
                reference(
                    args.reference_src, args.presets, args.agents, args.iterations, args.compile
                )
            )
    results = median_of(runs)
    if args.json:
        print(json.dumps(results))
        return
    ref = median_of(ref_runs) if ref_runs else {}
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=False
    ).stdout.strip()
    lines = [
        "# Training throughput",
        "",
        f"Measured {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC at commit "
        f"{commit or 'unknown'} with `python benchmarks/train_throughput.py --presets "
        f"{' '.join(args.presets)} --agents {' '.join(args.agents)} --iterations "
        f"{args.iterations}"
        + (" --compile" if args.compile else "")
        + (f" --device {args.device}" if args.device != "cpu" else "")
        + (f" --num-envs {args.num_envs}" if args.num_envs else "")
        + (" --update-threads-ab" if args.update_threads_ab else "")
        + (f" --repeats {args.repeats}" if args.repeats > 1 else "")
        + (" --reference-src REF/src`" if args.reference_src else "`")
        + ".",
        "",
        f"Machine: {cpu_model()}, {usable_cores()} usable cores (load {load_average()}), "
        f"torch {torch.__version__}, 1 torch thread for the rollout, the runs' `update_threads` "
        "for the update (every core for minibatches of >= 1,024 samples)"
        + (f", networks and PPO on {torch.cuda.get_device_name()}" if args.device != "cpu" else "")
        + ".",
        "",
        "Ceiling: the raw physics of each row's own motion, measured right after it "
        "(`mujoco.rollout` replaying the control steps its timed iterations visited: from "
        "each recorded state, 10 substeps with the actuators off and the mean joint torques "
        "the env applied held constant; the faster of MuJoCo's thread pool and the env's "
        "`ThreadedRollout`; `benchmarks/env_throughput.py`, `ReplayCeiling`). The last "
        "share column takes MuJoCo's thread pool alone (`mujoco.rollout` as it comes, the "
        "issue's ceiling), paired per iteration the same way.",
        "",
        "| preset | agent | envs | training SPS | ceiling | of ceiling | of ceiling, paired per "
        "iteration | of MuJoCo's pool, paired | collection us/step | "
        "of which simulation | outside the simulation | update us/sample | CPU stolen |"
        + (
            " reference SPS | speed-up | reference simulation | reference outside the "
            "simulation | update speed-up |"
            if ref
            else ""
        ),
        "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
        " ---: |" + (" ---: | ---: | ---: | ---: | ---: |" if ref else ""),
    ]
    for key, r in results.items():
        preset, agent = key.split("/")
        row = (
            f"| {preset} | {agent} | {r['num_envs']} | {r['SPS']:,.0f} | "
            f"{fmt_ceiling(r, [run[key] for run in runs])} | "
            f"{r['collect_us']:.1f} | "
            f"{r['simulation_us']:.1f} | {r['outside_us']:.1f} | {r['update_us']:.1f} | "
            f"{fmt_stolen(r)} |"
        )
        old = ref.get(key)
        if old:
            sps, update = (
                fmt_speedup(paired_speedups(runs, ref_runs, key, field))
                for field in ("SPS", "update_us")
            )
            row += (
                f" {old['SPS']:,.0f} | {sps} | {old['simulation_us']:.1f} | "
                f"{old['outside_us']:.1f} | {update} |"
            )
        elif ref:
            row += " - | - | - | - | - |"
        lines.append(row)
        print(row)
    if args.reference_src:
        ref_commit = subprocess.run(
            ["git", "-C", args.reference_src, "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            check=False,
        ).stdout.strip()
        lines += ["", f"`REF`: a checkout of commit {ref_commit or 'unknown'}."]
    lines += [
        "",
        "Collection is everything in a rollout step (agent, normaliser, simulation, storage,",
        "episode bookkeeping, GAE), per control step of one env; outside the simulation: all",
        "of that but `env.step`; the update is the PPO epochs",
        "over the rollout, per sample. `+ compile`: `ppo.compile=true` (`torch.compile` of",
        "the minibatch loss and, since 27 Nov 2026, of the rollout's policy step and reward",
        "scaling; a reference tree compiles what it compiled). Reference: the same script",
        "and settings with the",
        "package of another source tree (`REF`, named below), measured in the same run.",
        "With `--repeats N`: each figure is the median of N measurements, the rows, the",
        "reference taken in turn; a speed-up is the median of the N paired",
        "ones (each repeat's code against the reference measured right after it), their",
        "range in brackets; the share of the ceiling is the medians' ratio, and in brackets",
        "the lowest and highest of the N repeats, each against its own ceiling. Paired per",
        "iteration: each timed iteration's control steps per second over the ceiling of that",
        "iteration's motion replayed right after it (the better of two replays, as for the",
        "ceiling; within seconds: a machine whose speed drifts slows both alike), the median",
        "over the iterations. CPU",
        "stolen: the share of the machine's CPU time that its",
        "hypervisor gave to something else (`steal` in `/proc/stat`), during the row's timed",
        "iterations / during its ceiling: on a shared host, a neighbour's load.",
        "",
    ]
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text("\n".join(lines))
    print(f"written {args.output}")


if __name__ == "__main__":
    main()
