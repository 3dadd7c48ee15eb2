"""`cpg-actor eval`: deterministic evaluation of a trained run; traces, figures (and a video) on
disk.

Next to the traces: ``training_curves.png`` and ``traces.png`` for every run, and the figures of
what the env reports (its step ``info``): with foot contacts, a gait diagram
(``gait_diagram.png``); with a forward-speed command, commanded vs measured forward speed
(``forward_speed.png``). The video shows one episode of the agent's own env, drawn by the env's
``render_frame``.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from cpg_actor.envs.config import SIMULATORS
from cpg_actor.plots import draw_gait_diagram, save_figure
from cpg_actor.progress import metrics_text

HELP = "evaluate a trained run deterministically; save per-step traces, figures (and a video)"
# the figures drawn where the traces have what they need (the quadruped's), next to the traces
GAIT_FIGURE = "gait_diagram.png"
SPEED_FIGURE = "forward_speed.png"
FIGURES = (GAIT_FIGURE, SPEED_FIGURE)  # kept unless --overwrite, as the traces
SPEED_SMOOTHING = 0.5  # s: the running mean drawn over the measured forward speed


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("run_dir", help="a run directory written by `cpg-actor train`")
    parser.add_argument(
        "--checkpoint", default=None, help="checkpoint file (default RUN_DIR/checkpoints/last.pt)"
    )
    parser.add_argument(
        "--episodes", type=int, default=5, help="episodes, run in parallel (default 5)"
    )
    parser.add_argument(
        "--sim",
        default=None,
        choices=SIMULATORS,
        help="physics backend (default: the run's)",
    )
    parser.add_argument("--seed", type=int, default=1000, help="environment seed (default 1000)")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="env.KEY=VALUE",
        help="override a field of the run's env config for this evaluation (value read as "
        "YAML, repeatable), e.g. --set env.command_range=[0.5,0.5]",
    )
    parser.add_argument("--video", default=None, help="write an mp4 of the first episode here")
    parser.add_argument(
        "--output", default=None, help="traces file (default RUN_DIR/eval/traces.npz)"
    )
    parser.add_argument(
        "--overwrite", action="store_true", help="replace existing traces / figures / video"
    )
    parser.add_argument(
        "--video-only",
        action="store_true",
        help="with --video: record the video only (a run already evaluated keeps its traces)",
    )


def run(args: argparse.Namespace) -> int:
    from cpg_actor.config import TrainConfig, apply_dict, check_seed, parse_override
    from cpg_actor.evaluation import finite_mean
    from cpg_actor.policy import load_policy

    check_seed(args.seed)
    run_dir = Path(args.run_dir)
    config_path = run_dir / "config.yaml"
    if not config_path.is_file():
        raise FileNotFoundError(
            f"{config_path} does not exist; is {run_dir} a training run directory?"
        )
    if args.episodes < 1:
        raise ValueError(f"--episodes must be >= 1, got {args.episodes}")
    checkpoint = Path(args.checkpoint) if args.checkpoint else run_dir / "checkpoints" / "last.pt"
    output = Path(args.output) if args.output else run_dir / "eval" / "traces.npz"
    if output.suffix != ".npz":
        raise ValueError(f"--output must end in .npz, got {output}")
    if args.video_only and not args.video:
        raise ValueError("--video-only needs --video PATH")
    if not checkpoint.is_file():
        raise FileNotFoundError(f"checkpoint {checkpoint} does not exist")
    config = TrainConfig.load(config_path)
    if args.sim is not None:
        config.env.sim = args.sim
    for text in args.set:
        override = parse_override(text)
        if set(override) != {"env"}:
            raise ValueError(f"--set {text!r}: eval overrides env fields only (env.KEY=VALUE)")
        apply_dict(config, override, "")
    if args.set:
        config.validate()
    kept = [] if args.video_only else [output, *(output.parent / name for name in FIGURES)]
    for path in [*kept, *([Path(args.video)] if args.video else [])]:
        if path.exists() and not args.overwrite:
            raise FileExistsError(f"{path} exists; pass --overwrite to replace it")

    policy = load_policy(checkpoint, env_config=config.env)
    if policy.config.agent != config.agent:
        raise ValueError(
            f"checkpoint {checkpoint} was trained with agent '{policy.config.agent}', "
            f"this run uses '{config.agent}'"
        )
    if args.video_only:
        record_video(policy, config, Path(args.video), args.seed, args.overwrite)
        print(f"video in {args.video}")
        return 0
    traces = evaluate(policy, config, args.episodes, seed=args.seed)

    output.parent.mkdir(parents=True, exist_ok=True)
    tmp = output.with_name(f".{output.stem}.tmp{os.getpid()}.npz")
    try:  # written next to it, then renamed: an existing file is replaced whole or not at all
        np.savez(tmp, **traces)
        os.replace(tmp, output)
    finally:
        tmp.unlink(missing_ok=True)
    names = [str(name) for name in traces["metric_names"]]  # the env's (hop_height)
    for i in range(args.episodes):
        metrics = metrics_text({name: traces[name][i] for name in names})
        print(
            f"episode {i}: return {traces['episode_return'][i]:.3f}, "
            f"{metrics + ', ' if metrics else ''}{traces['length'][i]} steps"
        )
    means = metrics_text({f"mean {name}": finite_mean(traces[name]) for name in names})
    print(
        f"mean return {traces['episode_return'].mean():.3f}{', ' + means if means else ''} "
        f"over {args.episodes} episodes; traces in {output}"
    )
    figures = plot_training_curves(
        run_dir / "metrics.jsonl", output.parent / "training_curves.png", traces["metric_names"]
    )
    figures += plot_traces(traces, output.parent / "traces.png")
    figures += plot_gait(traces, output.parent / GAIT_FIGURE)  # [] where the env has no feet
    figures += plot_speed(traces, output.parent / SPEED_FIGURE)
    for figure in figures:
        print(f"figure {figure}")
    if args.video:
        record_video(policy, config, Path(args.video), args.seed, args.overwrite)
        print(f"video in {args.video}")
    return 0


def evaluate(policy, config, episodes: int, seed: int) -> dict[str, np.ndarray]:
    """Run ``episodes`` envs of the agent's own environment to the end of their first episode
    with the mean action; return traces ``(T, E, ...)`` (rows after an env's episode ended are
    NaN)."""
    from cpg_actor.agents import get_agent_spec
    from cpg_actor.evaluation import evaluate as run_episodes

    env = get_agent_spec(config.agent).make_env(
        episodes, config.env, config.env_threads, config.agent_config
    )
    try:
        traces = run_episodes(
            policy,
            env,
            seed=seed,
            control_dt=float(config.env.control_dt),
            max_steps=int(getattr(config.env, "episode_steps", 10_000)),
        )
    finally:
        env.close()
    traces["agent"] = np.array(config.agent)
    return traces


def record_video(policy, config, path: Path, seed: int, overwrite: bool) -> None:
    """One deterministic episode in the agent's own environment (one env), rendered offscreen
    by its ``render_frame`` (the hopper's or the quadruped's scene) and encoded as it runs."""
    from cpg_actor.agents import get_agent_spec
    from cpg_actor.envs import write_video

    env = get_agent_spec(config.agent).make_env(1, config.env, 1, config.agent_config)

    def frames():
        obs, _ = env.reset(seed=seed)
        policy.reset(1)
        yield env.render_frame(0)
        for _ in range(int(config.env.episode_steps)):
            obs, _, terminated, truncated, _ = env.step(policy.act(obs).action)
            if terminated[0] or truncated[0]:
                break  # the env has already reset: the frame would show the next episode
            yield env.render_frame(0)

    try:
        write_video(frames(), path, fps=round(1.0 / config.env.control_dt), overwrite=overwrite)
    finally:
        env.close()


def plot_training_curves(metrics: Path, path: Path, metric_names=()) -> list[Path]:
    """Episode return and an episode metric against training steps, from ``metrics.jsonl``:
    the hop height, the quadruped's speed error, else the first of the env's ``metric_names``
    that was logged."""
    import json

    if not metrics.is_file():
        return []
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [json.loads(line) for line in metrics.read_text().splitlines() if line.strip()]
    steps = np.array([r["global_step"] for r in rows], dtype=float)
    labels = {"hop_height": "mean hop height (m)", "speed_error": "mean speed error (m/s)"}
    logged = [name for name in (*labels, *map(str, metric_names))
              if any(r.get(f"charts/{name}") is not None for r in rows)]  # fmt: skip
    metric = logged[0] if logged else "hop_height"
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.5))
    for ax, key, label in (
        (axes[0], "charts/episode_return", "mean episode return"),
        (axes[1], f"charts/{metric}", labels.get(metric, f"mean {metric}")),
    ):
        values = np.array([np.nan if r.get(key) is None else r[key] for r in rows], dtype=float)
        ax.plot(steps, values)
        ax.set_xlabel("control steps")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    fig.suptitle(str(metrics.parent.name))
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
    plt.close(fig)
    return [path]


def plot_traces(traces: dict[str, np.ndarray], path: Path) -> list[Path]:
    """Episode 0: desired vs measured positions, desired velocities, heights (paper Fig. 6-7)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = traces["time"]
    panels = [
        ("position (rad)", "desired_position", "measured_position"),
        ("desired velocity (rad/s)", "desired_velocity", None),
    ]
    if "theta_dot" in traces:
        panels += [("theta_dot (rad/s)", "theta_dot", None), ("r_ddot (rad/s^2)", "r_ddot", None)]
    # the robot's first joints (traces saved before joint names were: the hopper's two)
    joints = [str(j) for j in traces.get("joint_names", ("HFE", "KFE"))][:3]
    heights = "hip_height" in traces
    rows = len(panels) + int(heights)
    fig, axes = plt.subplots(rows, 1, figsize=(9, 2.2 * rows), sharex=True)
    for ax, (label, key, measured) in zip(axes, panels, strict=False):
        if key not in traces:
            continue
        for j, joint in enumerate(joints):
            ax.plot(
                t, traces[key][:, 0, j], label=joint if measured is None else f"{joint} desired"
            )
            if measured is not None and measured in traces:
                ax.plot(t, traces[measured][:, 0, j], "--", label=f"{joint} measured")
        ax.set_ylabel(label)
        ax.legend(fontsize=7, loc="upper right")
        ax.grid(alpha=0.3)
    if not heights:  # a robot without a hip height (the quadruped)
        axes[-1].set_xlabel("time (s)")
        fig.tight_layout()
        save_figure(fig, path)
        plt.close(fig)
        return [path]
    axes[-1].plot(t, traces["hip_height"][:, 0], label="hip")
    axes[-1].plot(t, traces["foot_height"][:, 0], ":", label="foot")
    axes[-1].set_ylabel("height (m)")
    axes[-1].set_xlabel("time (s)")
    axes[-1].legend(fontsize=7, loc="upper right")
    axes[-1].grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
    return [path]


def _episode(traces: dict[str, np.ndarray], key: str, episode: int = 0) -> np.ndarray:
    """The rows of ``key`` while ``episode`` ran (its NaN tail cut); ``time`` is shared."""
    rows = traces[key][: int(traces["length"][episode])]
    return rows if key == "time" else rows[:, episode]


def plot_gait(traces: dict[str, np.ndarray], path: Path) -> list[Path]:
    """Episode 0's foot contacts over its last seconds, one row per foot (as ``cpg-actor
    gaits`` draws them), with each foot's duty factor; nothing where the env reports no
    contacts."""
    if "foot_contact" not in traces:
        return []
    from matplotlib.figure import Figure

    contact = _episode(traces, "foot_contact") > 0.5
    feet = [str(name) for name in traces["foot_names"]]
    dt, time = float(traces["control_dt"]), _episode(traces, "time")
    fig = Figure(figsize=(9.0, 0.35 * len(feet) + 1.4), layout="constrained")
    axis = fig.subplots()
    draw_gait_diagram(axis, contact, dt, feet, first_time=float(time[0]))
    duty = ", ".join(f"{foot} {share:.2f}" for foot, share in zip(feet, contact.mean(0),
                                                                   strict=True))  # fmt: skip
    axis.set_title(f"episode 0 ({len(contact) * dt:g} s): duty factor {duty}",
                   fontsize="medium", loc="left")  # fmt: skip
    axis.set_xlabel("time (s); bars: foot on the ground")
    save_figure(fig, path)
    return [path]


def plot_speed(traces: dict[str, np.ndarray], path: Path) -> list[Path]:
    """Commanded vs measured forward speed of every episode over time (the measured one as a
    running mean over ``SPEED_SMOOTHING`` s, episode 0's also raw); nothing where the env
    reports no forward-speed command."""
    if "base_forward_speed" not in traces or "command" not in traces:
        return []
    from matplotlib.figure import Figure

    dt = float(traces["control_dt"])
    fig = Figure(figsize=(9.0, 3.6), layout="constrained")
    axis = fig.subplots()
    for episode in range(len(traces["length"])):
        time = _episode(traces, "time", episode)
        measured = _episode(traces, "base_forward_speed", episode)
        # centred, over fewer rows at the ends (numpy's "same" needs it no longer than the data)
        kernel = np.ones(max(1, min(round(SPEED_SMOOTHING / dt), len(measured))))
        mean = np.convolve(measured, kernel, "same") / np.convolve(
            np.ones_like(measured), kernel, "same"
        )
        command = _episode(traces, "command", episode)[:, 0]
        color = f"C{episode % 10}"
        if episode == 0:
            axis.plot(time, measured, color=color, alpha=0.3, lw=0.8)
        axis.plot(time, mean, color=color,
                  label=f"episode {episode}: measured ({SPEED_SMOOTHING:g} s mean)")  # fmt: skip
        axis.plot(time, command, "--", color=color, label=f"episode {episode}: commanded")
    axis.set_xlabel("time (s)")
    axis.set_ylabel("forward speed (m/s)")
    axis.grid(alpha=0.3)
    axis.legend(fontsize=7, loc="upper left", ncols=2)
    axis.set_title("commanded vs measured forward speed (episode 0 raw, faint)",
                   fontsize="medium", loc="left")  # fmt: skip
    save_figure(fig, path)
    return [path]
