"""The untrained prior with the whole command: the open-loop gait CPG of the ``leg`` layout
with planar steps (``agent_config.cpg_planar_steps``: each leg's drive and step direction
from the command, :mod:`cpg_actor.robots.common.quadruped.planar_drive`), no feedback, no
learning, on flat ground on MuJoCo. For each command of the evaluation protocol's grid
(``cpg_actor.robustness.protocol.GRID``) held for ``--seconds``, ``--robots`` robots (the task's
reset noise, seeds 0..) walk it; the table gives the mean achieved forward and lateral speed
(base frame, m/s) and yaw rate (rad/s) over the second half of the run, next to the command,
and the robots that fell. It shows how much of the command the prior alone walks (the
feedback corrects the rest); not a tracking target.

    python benchmarks/planar_prior.py [--robot go1 anymal] [--gait trot] [--seconds 6]
        [--robots 4] [--output benchmarks/results/planar_prior.md]
"""

from __future__ import annotations

import argparse
import sys

import numpy as np
import torch

from bench_report import measured, write
from cpg_actor.robots.registry import get_robot
from cpg_actor.robustness.protocol import GRID

# the evaluation protocol's command grid: name -> (forward m/s, lateral m/s, yaw rate rad/s)
COMMANDS = {c.name: (c.vx, c.vy, c.yaw) for c in GRID}


def base_velocity(qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
    """(N, 3): the base's forward and lateral speed in its heading frame (m/s) and its yaw
    rate (rad/s, the body frame's z: the free joint's angular velocity)."""
    w, x, y, z = (qpos[:, 3 + i] for i in range(4))
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    c, s = np.cos(yaw), np.sin(yaw)
    vx, vy = qvel[:, 0], qvel[:, 1]
    return np.stack([c * vx + s * vy, -s * vx + c * vy, qvel[:, 5]], axis=1)


def walk(robot_name: str, command, gait: str, seconds: float, robots: int) -> dict:
    """The open-loop prior of ``robot_name`` under ``command`` for ``seconds``: the mean
    achieved (vx, vy, yaw rate) over the second half, per robot, and which robots fell."""
    robot = get_robot(robot_name)
    config = robot.config_class().replace(
        command_range=(command[0], command[0]), lateral_range=(command[1], command[1]),
        yaw_range=(command[2], command[2]), episode_seconds=seconds + 1.0,
    )  # fmt: skip
    env = robot.make(robots, config, num_threads=1)
    layout = robot.cpg_layouts()["leg"]
    spec = env.robot
    cpg = layout.preset(spec.control_dt, gait=gait).double()
    pattern = layout.pattern(spec.nominal_pose).double()
    drive, direction = layout.planar_drive().double()(
        torch.tensor([command] * robots, dtype=torch.float64)
    )
    state = cpg.initial_state(robots)
    env.reset(seed=0)
    steps = round(seconds / spec.control_dt)
    velocities, fell = [], np.zeros(robots, dtype=bool)
    with torch.no_grad():
        for k in range(steps):
            _, state = cpg(state, drive)
            joints = pattern(state.phase, state.amplitude, direction).numpy()
            _, _, terminated, truncated, _ = env.step(joints)
            fell |= terminated
            if k >= steps // 2:
                velocities.append(base_velocity(env.qpos, env.qvel))
    env.close()
    return {"achieved": np.mean(velocities, axis=0), "fell": fell}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robot", nargs="+", default=["go1", "anymal"])
    parser.add_argument("--gait", default="trot")
    parser.add_argument("--seconds", type=float, default=6.0)
    parser.add_argument("--robots", type=int, default=4)
    parser.add_argument("--output", default="benchmarks/results/planar_prior.md")
    args = parser.parse_args(argv)
    command_line = "python benchmarks/planar_prior.py " + " ".join(sys.argv[1:] if argv is None
                                                                    else argv)  # fmt: skip
    lines = [
        "# The untrained prior with the whole command (open-loop CPG, planar steps)",
        "",
        measured(command_line.strip()),
        "",
        f"Open-loop {args.gait} of the `leg` layout with planar steps, no feedback, flat "
        f"ground, MuJoCo; {args.robots} robots (the task's reset noise, seeds 0..) per command, "
        f"{args.seconds:g} s each; means over the second half (base heading frame). vx, vy in "
        "m/s, yaw rate in rad/s.",
        "",
        "| robot | command | commanded (vx, vy, yaw) | achieved vx | achieved vy | achieved yaw "
        "| fell |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    for name in args.robot:
        for label, command in COMMANDS.items():
            out = walk(name, command, args.gait, args.seconds, args.robots)
            mean = out["achieved"].mean(axis=0)
            lines.append(f"| {name} | {label} | ({command[0]:+.1f}, {command[1]:+.1f}, "
                         f"{command[2]:+.1f}) | {mean[0]:+.2f} | {mean[1]:+.2f} | "
                         f"{mean[2]:+.2f} | {int(out['fell'].sum())}/{args.robots} |")  # fmt: skip
    write(args.output, lines)


if __name__ == "__main__":
    main()
