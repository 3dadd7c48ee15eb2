"""How far the open-loop trot gets on rough ground: falls per terrain level and kind.

    python benchmarks/terrain_trot.py [--robot go1] [--robots 4] [--seconds 20]
        [--levels 10] [--command 0.5] [--floor-contacts auto]
        [--output benchmarks/results/terrain_trot.md]

The robot's training CPG layout (``leg``, the foot-space pattern) in its trot preset, open
loop at the drive of a ``--command`` m/s forward command (no learning, no feedback), on flat
ground and then on each level of the default terrain (``env.terrain``: every kind, ``--levels``
levels, the curriculum off so that every robot stays on its level): ``--robots`` robots per
kind, one episode of ``--seconds`` each, started on their tile within 1 m of its centre. A
row per level: the robots of each kind that fell (the env's ``fell``: base too low over the
ground, tilted past ``fall_tilt`` or touching the ground), and the mean forward speed of
those that did not. What a policy has to add to the prior on each kind. ``--floor-contacts``:
the env's ``floor_contacts`` (``feet``: the feet alone touch the ground, the faster
collisions), on flat ground and terrain alike.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import torch

from bench_report import measured, write
from cpg_actor.machine import cpu_model
from cpg_actor.robots.registry import get_robot
from cpg_actor.terrain import KINDS


def trot(
    robot,
    num_envs: int,
    seconds: float,
    command: float,
    terrain: dict | None,
    floor_contacts: str = "auto",
):
    """One episode of the open-loop trot for ``num_envs`` robots: (fell (N,) bool, mean forward
    speed (N,) m/s, the env's control steps per second of ``env.step``) on ``terrain`` (a
    mapping of its fields; None: flat)."""
    values = {"command_range": (command, command), "episode_seconds": seconds,
              "floor_contacts": floor_contacts}  # fmt: skip
    if terrain is not None:
        values["terrain"] = terrain
    env = robot.make(num_envs, robot.config_class.from_dict(values))
    env.reset(seed=0)
    layout = robot.cpg_layouts()["leg"]
    cpg = layout.preset(env.config.control_dt, gait="trot").double()
    pattern = layout.pattern(env.robot.nominal_pose).double()
    state = cpg.initial_state(num_envs)
    drive = torch.full((num_envs, cpg.num_oscillators), command, dtype=torch.float64)
    fell, speed = np.zeros(num_envs, dtype=bool), np.full(num_envs, np.nan)
    stepping = 0.0
    with torch.no_grad():
        for _ in range(env.config.episode_steps):
            _, state = cpg(state, drive)
            action = pattern(state.phase, state.amplitude).numpy()
            begin = time.perf_counter()
            _, _, terminated, truncated, info = env.step(action)
            stepping += time.perf_counter() - begin
            ended = (terminated | truncated) & np.isnan(speed)  # the first episode only
            fell |= terminated & ended
            speed[ended] = info["episode_metrics"]["forward_speed"][ended]
    env.close()
    return fell, speed, env.config.episode_steps * num_envs / stepping


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="go1")
    parser.add_argument("--robots", type=int, default=4, help="per kind and level")
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--levels", type=int, default=10)
    parser.add_argument("--command", type=float, default=0.5, help="m/s")
    parser.add_argument("--floor-contacts", default="auto", help="the env's floor_contacts")
    parser.add_argument("--output", default="benchmarks/results/terrain_trot.md")
    args = parser.parse_args()
    if args.robots < 1 or args.levels < 1 or not args.seconds > 0:
        parser.error("--robots and --levels must be >= 1 and --seconds positive")
    robot = get_robot(args.robot)
    n = args.robots * len(KINDS)  # env i walks kind i % len(KINDS)
    rows = []
    fell, speed, flat_sps = trot(robot, n, args.seconds, args.command, None, args.floor_contacts)
    falls = [f"{fell.sum()}/{n}"] + ["-"] * (len(KINDS) - 1)
    rows.append(("flat ground", falls, np.nanmean(np.where(fell, np.nan, speed)), 1.0))
    for level in range(args.levels):
        terrain = {"kinds": list(KINDS), "levels": args.levels, "curriculum": False,
                   "start_level": level}  # fmt: skip
        fell, speed, sps = trot(robot, n, args.seconds, args.command, terrain, args.floor_contacts)
        kind = np.arange(n) % len(KINDS)
        falls = [f"{fell[kind == k].sum()}/{args.robots}" for k in range(len(KINDS))]
        standing = np.where(fell, np.nan, speed)
        mean = np.nanmean(standing) if (~fell).any() else np.nan
        rows.append((str(level), falls, mean, sps / flat_sps))
        print(level, falls, f"{sps / flat_sps:.2f}", flush=True)
    command = (
        f"python benchmarks/terrain_trot.py --robot {args.robot} --robots {args.robots} "
        f"--seconds {args.seconds:g} --levels {args.levels} --command {args.command:g}"
        + (f" --floor-contacts {args.floor_contacts}" if args.floor_contacts != "auto" else "")
    )
    lines = [
        f"# The open-loop trot on rough ground ({robot.name})",
        "",
        measured(command) + f" on {cpu_model()}.",
        "",
        f"The foot-space trot open loop at the drive of {args.command:g} m/s, one "
        f"{args.seconds:g} s episode per robot, {args.robots} robots per kind and level (flat: "
        f"{n} robots); falls, and the mean forward speed of the robots that did not fall. The "
        "default terrain (`env.terrain`), level l of L at (l + 1) / L of the top level's 0.1 m "
        "roughness, 0.4 slope and 0.2 m steps. Steps/s: the env's `step` on the level over "
        "flat ground's, the same number of robots (one run each, on a shared machine: "
        "indicative).",
        "",
        "| level | " + " | ".join(KINDS) + " | forward speed, m/s | steps/s vs flat |",
        "| --- | " + " | ".join("---" for _ in KINDS) + " | --- | --- |",
        *(f"| {level} | " + " | ".join(falls) + f" | {speed:.2f} | {ratio:.2f} |"
          for level, falls, speed, ratio in rows),
        "",
    ]  # fmt: skip
    write(args.output, lines)


if __name__ == "__main__":
    main()
