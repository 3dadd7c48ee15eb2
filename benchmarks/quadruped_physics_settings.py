"""What cheaper physics settings buy the quadrupeds, and whether their open-loop trot still holds.

    python benchmarks/quadruped_physics_settings.py [--robot go1 anymal] [--envs 256]
        [--rounds 3] [--trot-robots 32] [--trot-seconds 4]
        [--output benchmarks/results/quadruped_physics_settings.md]

Per robot and setting (the default: 2 ms x 10 substeps per 20 ms control step, elliptic
friction cones, ``impratio`` 100; then 4 ms x 5 and 5 ms x 4 substeps, pyramidal cones, a lower
``impratio``, and their combinations), the robot's MuJoCo env made with that setting
(``physics_dt`` and ``decimation`` through its config, the cone and ``impratio`` on its model):

* standing ceiling: ``mujoco.rollout`` of ``--envs`` robots from their reset pose, the nominal
  pose held, on the env's threads, a second of control steps: the faster of MuJoCo's pool and
  the env's ``ThreadedRollout``; rounds over the settings in turn, each setting's speed-up over
  the default measured in the same round, the median over the rounds;
* trot: the robot's training CPG layout (``leg``, the foot-space pattern) in its trot preset,
  open loop at the drive of a 0.5 m/s command, on ``--trot-robots`` robots for
  ``--trot-seconds`` (episodes of that length): the physics' control steps per second while it
  walks (the env's ``mujoco.rollout`` calls only, ``time.perf_counter``), falls, mean forward
  speed, speed error and foot slip (the env's episode metrics, ``docs/quadruped.md``).

It changes no default: the robots' settings are the lead's decision.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import torch

from bench_report import measured, write
from cpg_actor.machine import cpu_model, load_average, usable_cores
from cpg_actor.robots.common.mujoco_runtime import CONTROL_SPEC, mujoco
from cpg_actor.robots.common.threaded_rollout import ThreadedRollout
from cpg_actor.robots.registry import get_robot

ROBOTS = ("go1", "anymal")
COMMAND = 0.5  # m/s, the trot's
# name -> (physics_dt, decimation, cone, impratio); None: the robot's own. Every step is named
# in full: the robots' own differ (the Go1 steps 5 ms x 4, ANYmal B 2 ms x 10)
SETTINGS = {
    "default (2 ms x 10, elliptic, impratio 100)": (0.002, 10, None, None),
    "4 ms x 5": (0.004, 5, None, None),
    "5 ms x 4": (0.005, 4, None, None),
    "pyramidal cones": (0.002, 10, "pyramidal", None),
    "impratio 10": (0.002, 10, None, 10.0),
    "impratio 1": (0.002, 10, None, 1.0),
    "4 ms x 5, pyramidal": (0.004, 5, "pyramidal", None),
    "4 ms x 5, impratio 10": (0.004, 5, None, 10.0),
}
CONES = {"pyramidal": mujoco.mjtCone.mjCONE_PYRAMIDAL, "elliptic": mujoco.mjtCone.mjCONE_ELLIPTIC}


def make_env(robot, setting: tuple, num_envs: int, values: dict | None = None):
    """The robot's MuJoCo env under ``setting`` (module docstring)."""
    physics_dt, decimation, cone, impratio = setting
    values = dict(values or {})
    if physics_dt is not None:
        values.update(physics_dt=physics_dt, decimation=decimation)
    env = robot.make(num_envs, robot.config_class.from_dict(values))
    if cone is not None:
        env.model.opt.cone = CONES[cone]
    if impratio is not None:
        env.model.opt.impratio = impratio
    return env


def standing_rate(env, seconds: float = 1.0) -> float:
    """Control steps per second of ``mujoco.rollout`` of the env's robots from their reset
    pose, the nominal pose held (module docstring)."""
    env.reset(seed=0)
    model, n, threads = env.model, env.num_envs, env.num_threads
    decimation = env.config.decimation
    steps = max(1, round(seconds / env.config.control_dt))
    start = env._state.copy()
    state, out = start.copy(), np.zeros((n, decimation, start.shape[1]))
    control = np.tile(env._nominal, (n, decimation, 1))
    pool = mujoco.rollout.Rollout(nthread=threads if threads > 1 else 0)
    datas = [mujoco.MjData(model) for _ in range(threads)]
    threaded = ThreadedRollout(model, n, threads)
    chunk = max(1, -(-n // (4 * threads)))

    def pool_step() -> None:
        pool.rollout(
            [model] * n, datas, state, control, control_spec=CONTROL_SPEC, skip_checks=True,
            nstep=decimation, initial_warmstart=None, state=out, chunk_size=chunk,
        )  # fmt: skip

    def threaded_step() -> None:
        threaded.rollout(state, control, out, None, CONTROL_SPEC, decimation)

    best = 0.0
    try:
        for step in (pool_step, threaded_step):
            np.copyto(state, start)
            begin = time.perf_counter()
            for _ in range(steps):
                step()
                np.copyto(state, out[:, -1])
            best = max(best, steps * n / (time.perf_counter() - begin))
    finally:
        pool.close()
        threaded.close()
    return best


def trot(robot, setting: tuple, num_robots: int, seconds: float) -> dict[str, float]:
    """The open-loop trot under ``setting`` (module docstring)."""
    values = {"command_range": (COMMAND, COMMAND), "episode_seconds": seconds}
    env = make_env(robot, setting, num_robots, values)
    physics = 0.0
    rollout = env.stepper.rollout

    def timed(*args):
        nonlocal physics
        begin = time.perf_counter()
        rollout(*args)
        physics += time.perf_counter() - begin

    env.stepper.rollout = timed
    env.reset(seed=0)
    layout = robot.cpg_layouts()["leg"]
    cpg = layout.preset(env.config.control_dt, gait="trot").double()
    pattern = layout.pattern(env.robot.nominal_pose).double()
    state = cpg.initial_state(num_robots)
    drive = torch.full((num_robots, cpg.num_oscillators), COMMAND, dtype=torch.float64)
    ended: dict[str, list[float]] = {}
    steps = env.config.episode_steps
    with torch.no_grad():
        for _ in range(steps):
            _, state = cpg(state, drive)
            _, _, terminated, truncated, info = env.step(
                pattern(state.phase, state.amplitude).numpy()
            )
            done = terminated | truncated
            for name, values in info["episode_metrics"].items():
                ended.setdefault(name, []).extend(values[done].tolist())
            if done.any():  # the CPG of a robot that fell starts again, as its episode
                fresh = cpg.initial_state(num_robots)
                state = type(state)(*(torch.where(torch.as_tensor(done).reshape(
                    -1, *[1] * (new.dim() - 1)), new, old) for new, old in zip(
                    fresh, state, strict=True)))  # fmt: skip
    env.close()
    result = {name: float(np.nanmean(values)) if np.isfinite(values).any() else float("nan")
              for name, values in ended.items()}  # fmt: skip
    result["episodes"] = len(ended.get("fell", []))
    result["falls"] = int(np.nansum(ended.get("fell", [])))
    result["physics_sps"] = steps * num_robots / physics
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", nargs="+", choices=ROBOTS, default=list(ROBOTS))
    parser.add_argument("--envs", type=int, default=256, help="robots of the standing ceiling")
    parser.add_argument("--rounds", type=int, default=3, help="paired rounds of the ceiling")
    parser.add_argument("--seconds", type=float, default=1.0, help="simulated s per ceiling")
    parser.add_argument("--trot-robots", type=int, default=32)
    parser.add_argument("--trot-seconds", type=float, default=4.0)
    parser.add_argument("--output", default="benchmarks/results/quadruped_physics_settings.md")
    args = parser.parse_args()
    for name in ("envs", "rounds", "trot_robots"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')} must be >= 1, got {getattr(args, name)}")
    if not (args.seconds > 0 and args.trot_seconds > 0):
        parser.error("--seconds and --trot-seconds must be positive")
    rows = []
    for name in args.robot:
        robot = get_robot(name)
        rates = {setting: [] for setting in SETTINGS}
        for _ in range(args.rounds):  # the settings in turn: a drifting machine slows all alike
            for setting, values in SETTINGS.items():
                env = make_env(robot, values, args.envs)
                try:
                    rates[setting].append(standing_rate(env, args.seconds))
                finally:
                    env.close()
        default = next(iter(SETTINGS))
        for setting, values in SETTINGS.items():
            walk = trot(robot, values, args.trot_robots, args.trot_seconds)
            ratio = statistics.median(
                new / old for new, old in zip(rates[setting], rates[default], strict=True)
            )
            rows.append((name, setting, statistics.median(rates[setting]), ratio, walk))
            print(rows[-1], flush=True)
    walk_default = {name: walk for name, setting, _, _, walk in rows if setting.startswith("def")}
    command = (
        f"python benchmarks/quadruped_physics_settings.py --robot {' '.join(args.robot)} "
        f"--envs {args.envs} --rounds {args.rounds} --seconds {args.seconds:g} "
        f"--trot-robots {args.trot_robots} --trot-seconds {args.trot_seconds:g}"
    )
    lines = [
        "# Quadruped physics settings: what they save, and whether the trot holds",
        "",
        measured(command) + f", on {cpu_model()}, {usable_cores()} usable cores "
        f"(load {load_average()}), torch {torch.__version__}, mujoco {mujoco.__version__}.",
        "",
        "Standing ceiling: `mujoco.rollout` of the robots from their reset pose, the nominal "
        "pose held; trot: the open-loop foot-space trot at the drive of a "
        f"{COMMAND} m/s command, physics only (module docstring). Speed-ups are the median of "
        "the paired ones (each setting against the default in the same round); the trot's "
        "physics speed-up is from one run each. Each step is named in full (the robots' own "
        "differ).",
        "",
        "| robot | setting | standing ceiling, control steps/s | speed-up | trot physics, "
        "steps/s | speed-up | falls / episodes | forward speed, m/s | speed error, m/s | "
        "foot slip, m/s |",
        "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for name, setting, rate, ratio, walk in rows:
        base = walk_default[name]["physics_sps"]
        lines.append(
            f"| {name} | {setting} | {rate:,.0f} | {ratio:.2f}x | {walk['physics_sps']:,.0f} | "
            f"{walk['physics_sps'] / base:.2f}x | {walk['falls']} / {walk['episodes']} | "
            f"{walk['forward_speed']:.3f} | {walk['speed_error']:.3f} | "
            f"{walk['foot_slip']:.3f} |"
        )
    write(args.output, lines + [""])


if __name__ == "__main__":
    main()
