"""`cpg-actor gaits`: a robot's CPG gait presets, open loop (the quadrupeds': ANYmal B, the Go1).

Each gait preset of the robot's CPG layout (``--robot``, ``--layout``: the layout's ``gaits``
in the registry, :class:`cpg_actor.robots.plugin.CPGLayout`) drives ``--robots`` robots for
``--seconds`` with no learning and no feedback (the untrained ``cpg-actor-open-loop``'s mean
action), its drive d (eq. 3) set by the forward command ``--command``. It writes a gait diagram
(which foot is on the ground, per leg, over the last seconds of robot 0, one panel per gait,
with the measured forward speed; next to it one cycle of the gait's reference footfall pattern
over robot 0's) as a PNG, and a JSON summary per gait: falls, mean forward speed, the duty
factor of each leg (share of time on the ground) and each leg's touchdown phase relative to the
first leg (fraction of a cycle: the gait's table, if the robot keeps it). A robot whose CPG has
no gait presets (the hopper) is refused.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

HELP = "run a quadruped's CPG gait presets open loop; write a gait diagram and a summary"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from cpg_actor.robots.registry import ROBOTS

    parser.add_argument("--robot", default="anymal", choices=list(ROBOTS),
                        help="a robot whose CPG has gait presets (default anymal)")  # fmt: skip
    parser.add_argument("--gaits", nargs="+", default=None,
                        help="the gaits to run (default: every gait of the layout: trot, pace, "
                        "bound, pronk, walk on the quadrupeds)")  # fmt: skip
    parser.add_argument("--seconds", type=float, default=20.0, help="per run (default 20)")
    parser.add_argument("--robots", type=int, default=4, help="robots per gait (default 4)")
    # its own dest: argparse's "command" names the sub-command (error lines read it)
    parser.add_argument("--command", dest="forward_command", type=float, default=0.5,
                        help="forward command, m/s (default 0.5)")  # fmt: skip
    parser.add_argument(
        "--layout",
        default="",
        help="the robot's CPG layout (default: its first). The quadrupeds': joint, one "
        "oscillator per hip and knee joint (the default); leg, one per leg, a foot-space pattern",
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="gaits", help="folder for gaits.png and gaits.json")
    parser.add_argument("--overwrite", action="store_true", help="replace existing files")


def touchdown_phases(contact, dt: float, frequency: float) -> list[float]:
    """Each leg's mean touchdown time after the first leg's, as a fraction of the CPG's cycle,
    from a ``(T, 4)`` contact trace (NaN for a leg that never lands twice)."""
    import numpy as np

    period = 1.0 / frequency
    touch = [np.flatnonzero(contact[1:, leg] & ~contact[:-1, leg]) * dt for leg in range(4)]
    phases = []
    for leg in range(4):
        if len(touch[0]) < 2 or len(touch[leg]) < 2:
            phases.append(float("nan"))
            continue
        lags = [(t - touch[0][touch[0] <= t].max()) / period for t in touch[leg]
                if (touch[0] <= t).any()]  # fmt: skip
        angles = 2 * np.pi * np.asarray(lags)
        mean = math.atan2(np.sin(angles).mean(), np.cos(angles).mean()) / (2 * math.pi)
        phases.append(round(mean % 1.0, 3))
    return phases


REFERENCE_DUTY = 0.5  # share of a cycle a foot is drawn on the ground in the reference pattern


def draw_reference(
    axis, gait: str, legs: Sequence[str], footfall: Sequence[float], summary: dict | None = None
) -> None:
    """One cycle of ``gait``'s intended footfall pattern on ``axis``: per leg a grey bar from
    its touchdown at the gait's phase (``footfall``, fractions of a cycle, in the order of
    ``legs``), counted from the first leg's, for ``REFERENCE_DUTY`` of the cycle; under it, from
    ``summary`` (the robot's measured ``touchdown_phase`` and ``duty_factor``), the CPG's result
    in blue."""

    def cycle(start: float, duty: float) -> list[tuple[float, float]]:
        """The bar from ``start`` for ``duty`` of a cycle, split where it wraps past 1."""
        start %= 1.0
        return [(start, min(duty, 1.0 - start))] + ([(0.0, start + duty - 1.0)]
                                                      if start + duty > 1.0 else [])  # fmt: skip

    n = len(legs)
    for leg, (name, phase) in enumerate(zip(legs, footfall, strict=True)):
        row = n - 1 - leg
        offset = (phase - footfall[0]) % 1.0
        axis.broken_barh(cycle(offset, REFERENCE_DUTY), (row + 0.02, 0.38), color="0.6",
                         label=f"reference {gait}" if leg == 0 else None)  # fmt: skip
        measured = (summary or {}).get("touchdown_phase", {}).get(name)
        duty = (summary or {}).get("duty_factor", {}).get(name)
        if measured is not None and duty is not None and math.isfinite(measured):
            axis.broken_barh(cycle(measured, duty), (row - 0.4, 0.38), color="tab:blue",
                             label="CPG (robot 0)" if leg == 0 else None)  # fmt: skip
    axis.set_yticks(range(n), list(legs)[::-1])
    axis.set_ylim(-0.6, n - 0.4)
    axis.set_xlim(0.0, 1.0)
    axis.set_xticks([0, 0.25, 0.5, 0.75, 1.0])
    axis.grid(axis="x", alpha=0.3)


def gaits_figure(
    traces: dict,
    summary: dict,
    command: float,
    legs: Sequence[str],
    footfalls: Mapping[str, Sequence[float]],
):
    """Per gait a row: the gait diagram of robot 0 over its last seconds (left) and, next to
    it, one cycle of the gait's reference footfall pattern (``footfalls[gait]``) over the CPG's
    measured one (right: :func:`draw_reference`)."""
    import numpy as np
    from matplotlib.figure import Figure

    from cpg_actor.plots import draw_gait_diagram

    fig = Figure(figsize=(12.0, 1.7 * len(traces) + 1.0), layout="constrained")
    axes = np.atleast_2d(fig.subplots(len(traces), 2, width_ratios=(3, 1), squeeze=False))
    for (diagram, reference), (gait, (contact, dt)) in zip(axes, traces.items(), strict=True):
        draw_gait_diagram(diagram, contact, dt, legs)
        s = summary[gait]
        diagram.set_title(f"{gait}: {s['fell']} of {s['robots']} fell, forward speed "
                          f"{s['forward_speed']:.2f} m/s (command {command} m/s)",
                          fontsize="medium", loc="left")  # fmt: skip
        draw_reference(reference, gait, legs, footfalls[gait], s)
        reference.set_title(f"one cycle: {gait} reference (grey) vs CPG (blue)",
                            fontsize="small", loc="left")  # fmt: skip
    axes[-1, 0].set_xlabel("time (s); bars: foot on the ground (robot 0)")
    axes[-1, 1].set_xlabel(f"cycles after {legs[0]} touches down\n"
                           f"(reference: on the ground {REFERENCE_DUTY:g} of a cycle)")  # fmt: skip
    return fig


def gait_layout(robot_name: str, layout: str, gaits: Sequence[str] | None) -> tuple[str, Any]:
    """The name and :class:`~cpg_actor.robots.plugin.CPGLayout` of ``robot_name``'s CPG layout
    ``layout`` (empty: its first), checked to have the gaits ``gaits`` (None: any); a one-line
    ValueError otherwise."""
    from cpg_actor.robots.registry import ROBOTS, get_robot

    robot = get_robot(robot_name)
    layouts = robot.cpg_layouts()
    if not any(choice.gaits for choice in layouts.values()):
        with_gaits = [r.name for r in ROBOTS.values()
                      if any(c.gaits for c in r.cpg_layouts().values())]  # fmt: skip
        raise ValueError(f"--robot {robot.name}: its CPG has no gait presets (robots with gaits: "
                         f"{', '.join(with_gaits)})")  # fmt: skip
    name = layout or next(iter(layouts))
    if name not in layouts or not layouts[name].gaits:
        choices = [n for n, choice in layouts.items() if choice.gaits]
        raise ValueError(f"--layout {name}: the {robot.name}'s CPG layouts with gaits are "
                         f"{', '.join(choices)}")  # fmt: skip
    unknown = [gait for gait in gaits or () if gait not in layouts[name].gaits]
    if unknown:
        raise ValueError(f"--gaits {' '.join(unknown)}: the {robot.name}'s {name} layout has the "
                         f"gaits {', '.join(layouts[name].gaits)}")  # fmt: skip
    return name, layouts[name]


def run(args: argparse.Namespace) -> int:
    import numpy as np
    import torch

    from cpg_actor.config import MAX_EPISODES, check_count
    from cpg_actor.cpg.joint_map import JointMap
    from cpg_actor.files import atomic_write_text
    from cpg_actor.plots import save_figure
    from cpg_actor.robots.registry import get_robot
    from cpg_actor.training.evaluation import finite_mean

    if not (math.isfinite(args.seconds) and args.seconds > 0):
        raise ValueError(f"--seconds must be a positive number, got {args.seconds}")
    check_count(args.robots, "--robots", MAX_EPISODES)  # an env each, as an evaluation's
    robot = get_robot(args.robot)
    layout, cpg_layout = gait_layout(args.robot, args.layout, args.gaits)
    gaits = args.gaits or list(cpg_layout.gaits)
    out = Path(args.out)
    paths = (out / "gaits.png", out / "gaits.json")
    for path in paths:
        if path.exists() and not args.overwrite:
            raise FileExistsError(f"{path} exists; pass --overwrite to replace it")
    config = robot.config_class.from_dict(
        {
            "command_range": (args.forward_command, args.forward_command),
            "episode_seconds": args.seconds,
        }
    )
    summary, traces, legs = {}, {}, ()
    for gait in gaits:
        env = robot.make(args.robots, config)
        env.reset(seed=args.seed)
        dt, legs, pose = env.config.control_dt, env.foot_names, env.robot.nominal_pose
        cpg = cpg_layout.preset(dt, gait=gait).double()
        if cpg_layout.pattern is not None:
            pattern = cpg_layout.pattern(pose).double()
            joints = lambda output, state, p=pattern: p(state.phase, state.amplitude)  # noqa: E731
        else:
            joint_map = JointMap(pose, joints=cpg_layout.joints).double()
            joints = lambda output, state, m=joint_map: m(output.position)  # noqa: E731
        state = cpg.initial_state(args.robots)
        n = cpg.num_oscillators
        drive = torch.full((args.robots, n), max(args.forward_command, 0.0), dtype=torch.float64)
        contact, speed, fell = [], [], np.zeros(args.robots, dtype=bool)
        alive = np.ones(args.robots, dtype=bool)
        with torch.no_grad():
            for _ in range(env.config.episode_steps):
                output, state = cpg(state, drive)
                _, _, terminated, _, info = env.step(joints(output, state).numpy())
                fell |= terminated & alive
                alive &= ~terminated
                contact.append(info["contact"][0].copy())
                speed.append(np.where(alive, info["forward_speed"], np.nan))
        env.close()
        contact, speed = np.array(contact), np.array(speed)
        traces[gait] = (contact, dt)
        frequency = float(cpg.oscillator_parameters(drive[0]).frequency[0].detach())
        summary[gait] = {
            "fell": int(fell.sum()),
            "robots": args.robots,
            "forward_speed": round(finite_mean(speed), 3),
            "duty_factor": dict(zip(legs, contact.mean(0).round(2).tolist(), strict=True)),
            "touchdown_phase": dict(
                zip(legs, touchdown_phases(contact, dt, frequency), strict=True)
            ),
        }
        print(f"{gait}: {summary[gait]}")

    fig = gaits_figure(traces, summary, args.forward_command, legs, cpg_layout.gaits)
    fig.suptitle(f"Open-loop CPG gaits on {robot.model} ({layout} layout, {args.seconds:g} s, "
                 f"seed {args.seed})")  # fmt: skip
    save_figure(fig, paths[0])
    atomic_write_text(json.dumps({"robot": robot.name, "command": args.forward_command,
                                  "layout": layout, "seconds": args.seconds,
                                  "seed": args.seed, "gaits": summary}, indent=2) + "\n",
                      paths[1])  # fmt: skip
    print(f"wrote {paths[0]} and {paths[1]}")
    return 0
