"""`cpg-actor cpg-demo`: integrate the hopper CPG open-loop and plot x, theta_dot and r_ddot.

The three panels are the quantities of the paper's eq. 1 that its results figure (section V,
fig:cpg_output / fig:cpg_theta_dot / fig:cpg_r_dot_dot) shows for trained controllers: the
output x_i = r_i cos(theta_i) (the offset of each joint's desired position from the nominal
pose), the phase velocity theta_dot_i and the amplitude acceleration r_ddot_i.
Constant feedback (--xi, --kappa) shows how the feedback terms reshape them.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
from pathlib import Path

HELP = "integrate the hopper CPG for a few seconds and plot x, theta_dot and r_ddot to a PNG"

MAX_STEPS = 1_000_000


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--duration", type=float, default=3.0, help="simulated seconds (default 3.0)"
    )
    parser.add_argument(
        "--dt", type=float, default=0.01, help="time step in seconds (default 0.01: 100 Hz)"
    )
    parser.add_argument(
        "--xi",
        type=float,
        nargs="+",
        default=[0.0],
        metavar="XI",
        help="constant phase feedback xi, rad/s: one value, or one per oscillator (HFE KFE)",
    )
    parser.add_argument(
        "--kappa",
        type=float,
        nargs="+",
        default=[0.0],
        metavar="KAPPA",
        help="constant amplitude feedback kappa, rad/s^2: one value, or one per oscillator",
    )
    parser.add_argument(
        "--initial-amplitude",
        type=float,
        default=0.0,
        help="amplitude r at t = 0, rad (default 0: the oscillators start at rest)",
    )
    parser.add_argument(
        "--initial-phase",
        type=float,
        nargs=2,
        default=None,
        metavar=("HFE", "KFE"),
        help="phases theta at t = 0, rad (default: the preset's 0 and pi, already in antiphase)",
    )
    parser.add_argument(
        "--out", default="cpg_demo.png", help="PNG file to write (default cpg_demo.png)"
    )
    parser.add_argument("--overwrite", action="store_true", help="replace an existing file")


def _feedback(name: str, values: list[float], joints: tuple[str, ...]) -> list[float]:
    if len(values) == 1:
        values = values * len(joints)
    if len(values) != len(joints):
        raise ValueError(
            f"--{name} takes one value or one per oscillator ({' '.join(joints)}), "
            f"got {len(values)}"
        )
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"--{name} must be finite, got {values}")
    return values


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def demo_figure(t, x, theta_dot, r_ddot, values, dt, phase0, xi_values, kappa_values):
    """The figure of the integrated CPG: the output x, theta_dot and r_ddot of each oscillator
    (rows ``t``), the preset's ``values`` in the title."""
    import numpy as np
    from matplotlib.figure import Figure  # no pyplot: no global state, Agg canvas

    from cpg_actor.robots.hopper.cpg import HOPPER_JOINTS, HOPPER_NOMINAL_POSE

    fig = Figure(figsize=(9.0, 7.5), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    # a colour and a line style per oscillator: the KFE's, dashed and thinner, drawn over the
    # HFE's, so that where they coincide (phase-locked: one phase velocity) both still show
    styles = ({"color": "tab:blue", "lw": 2.6}, {"color": "tab:orange", "lw": 1.3, "ls": "--"})
    colours = tuple(style["color"] for style in styles)
    for i, joint in enumerate(HOPPER_JOINTS):
        label = f"{joint}\n(nominal {HOPPER_NOMINAL_POSE[i]:+.2f} rad)"
        axes[0].plot(t, x[:, i], label=label, **styles[i])
        axes[1].plot(t, theta_dot[:, i], label=joint, **styles[i])
        axes[2].plot(t, r_ddot[:, i], label=joint, **styles[i])
        axes[0].axhline(values["amplitude"][i], color=colours[i], lw=0.6, ls=":")
        axes[0].axhline(-values["amplitude"][i], color=colours[i], lw=0.6, ls=":")
    axes[0].plot([], [], color="grey", lw=0.6, ls=":", label=r"$\pm\rho$")
    intrinsic = 2 * math.pi * values["frequency"]
    axes[1].axhline(intrinsic[0], color="grey", lw=0.8, ls="--", label=r"$2\pi\nu$")
    if np.allclose(theta_dot[:, 0], theta_dot[:, 1], rtol=1e-5, atol=1e-4):
        axes[1].set_title("HFE and KFE phase velocities are equal: the lines overlap",
                          fontsize="small", loc="left")  # fmt: skip
    axes[0].set_ylabel("output $x$: offset from\nthe nominal pose (rad)")
    axes[1].set_ylabel("phase velocity\n" r"$\dot\theta$ (rad/s)")
    axes[2].set_ylabel("amplitude acceleration\n" r"$\ddot r$ (rad/s$^2$)")
    axes[2].set_xlabel("time (s)")
    for axis, minimum_span in zip(axes, (0.1, 2.0, 2.0), strict=True):
        # a flat trace must look flat, not like float32 round-off magnified by autoscaling
        axis.ticklabel_format(axis="y", useOffset=False)
        low, high = axis.get_ylim()
        if high - low < minimum_span:
            middle = 0.5 * (low + high)
            axis.set_ylim(middle - minimum_span / 2, middle + minimum_span / 2)
        axis.grid(alpha=0.3)
        axis.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    phi = values["phase_bias"][0, 1]
    feedback = any(v != 0 for v in xi_values + kappa_values)
    mode = "constant feedback" if feedback else "open loop (no feedback)"
    fig.suptitle(
        f"Hopper CPG, {mode}: nu = {values['frequency'][0]:.2f} Hz, "
        f"rho = ({values['amplitude'][0]:.2f}, {values['amplitude'][1]:.2f}) rad, "
        f"a = {values['convergence'][0]:.0f} 1/s, w = {values['coupling_weight'][0, 1]:.0f}, "
        f"phi = {phi:.2f} rad\n"
        f"dt = {dt} s, theta(0) = ({phase0[0]:.2f}, {phase0[1]:.2f}) rad, "
        f"xi = {xi_values} rad/s, "
        f"kappa = {kappa_values} rad/s$^2$",
        fontsize="medium",
    )
    return fig


def run(args: argparse.Namespace) -> int:
    import numpy as np
    import torch

    from cpg_actor.robots.hopper.cpg import HOPPER_JOINTS, hopper_cpg

    out = Path(args.out)
    if out.suffix.lower() != ".png":
        raise ValueError(f"--out must be a .png file, got {out}")
    if out.is_dir():
        raise ValueError(f"--out {out} is a directory")
    if out.exists() and not args.overwrite:
        raise FileExistsError(f"{out} exists; pass --overwrite to replace it")
    if not (math.isfinite(args.duration) and args.duration > 0):
        raise ValueError(f"--duration must be a positive number of seconds, got {args.duration}")
    if not (math.isfinite(args.dt) and args.dt > 0):
        raise ValueError(f"--dt must be a positive number of seconds, got {args.dt}")
    steps = round(args.duration / args.dt)
    if not 2 <= steps <= MAX_STEPS:
        raise ValueError(f"--duration / --dt gives {steps} steps; between 2 and {MAX_STEPS}")
    if not (math.isfinite(args.initial_amplitude) and args.initial_amplitude >= 0):
        raise ValueError(f"--initial-amplitude must be >= 0, got {args.initial_amplitude}")
    if args.initial_phase is not None and not all(map(math.isfinite, args.initial_phase)):
        raise ValueError(f"--initial-phase must be finite, got {args.initial_phase}")
    xi_values = _feedback("xi", args.xi, HOPPER_JOINTS)
    kappa_values = _feedback("kappa", args.kappa, HOPPER_JOINTS)

    # -- integrate ------------------------------------------------------------------------
    net = hopper_cpg(args.dt)
    xi = torch.tensor(xi_values)
    kappa = torch.tensor(kappa_values)
    phase = None if args.initial_phase is None else torch.tensor(args.initial_phase)
    state = net.initial_state(1, amplitude=args.initial_amplitude, phase=phase)
    state0 = state
    x, theta_dot, r_ddot = [], [], []
    with torch.no_grad():
        for _ in range(steps):
            output, state = net(state, 0.0, xi, kappa)
            x.append(output.position[0])
            theta_dot.append(state.phase_velocity[0])
            r_ddot.append(state.amplitude_acceleration[0])
    x, theta_dot, r_ddot = (torch.stack(v).numpy() for v in (x, theta_dot, r_ddot))
    t = args.dt * np.arange(1, steps + 1)
    values = {k: v.detach().numpy() for k, v in net.parametrisation.values().items()}

    # -- plot -----------------------------------------------------------------------------
    phase0 = (float(state0.phase[0, 0]), float(state0.phase[0, 1]))
    fig = demo_figure(t, x, theta_dot, r_ddot, values, args.dt, phase0, xi_values, kappa_values)

    # -- write atomically -----------------------------------------------------------------
    out.parent.mkdir(parents=True, exist_ok=True)
    descriptor, temporary = tempfile.mkstemp(dir=out.parent, prefix=f".{out.name}.", suffix=".tmp")
    os.close(descriptor)
    try:
        fig.savefig(temporary, format="png", dpi=120)
        os.chmod(temporary, 0o666 & ~_umask())  # mkstemp makes it 0600; use a new file's mode
        if out.exists() and not args.overwrite:  # appeared while we were computing
            raise FileExistsError(f"{out} exists; pass --overwrite to replace it")
        os.replace(temporary, out)
    finally:
        if os.path.exists(temporary):
            os.unlink(temporary)

    last_second = t > t[-1] - 1.0
    amplitude = (x[last_second].max(0) - x[last_second].min(0)) / 2
    frequency = theta_dot[last_second].mean(0) / (2 * math.pi)
    summary = ", ".join(
        f"{joint} amplitude {amplitude[i]:.3f} rad at {frequency[i]:.2f} Hz"
        for i, joint in enumerate(HOPPER_JOINTS)
    )
    print(f"wrote {out} ({steps} steps of {args.dt} s); last second: {summary}")
    return 0
