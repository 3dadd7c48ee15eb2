"""`cpg-actor eval`: deterministic evaluation of a trained run; traces, figures (and a video) on
disk.

Next to the traces: ``training_curves.png`` (the return and the env's own episode metrics
against training steps) and ``traces.png`` (episode 0's joints, CPG and heights, per limb)
for every run, and the figures of what the env reports (its step ``info``): with foot
contacts, a gait diagram (``gait_diagram.png``); with a forward-speed command, commanded vs
measured forward speed (``forward_speed.png``). The video shows one episode of the agent's
own env, drawn by the env's ``render_frame``.

With ``--grid`` (a quadruped's run): the evaluation protocol instead
(:mod:`cpg_actor.robustness.protocol`): a fixed grid of velocity commands, each held for an
episode, and the payload and push checks; printed as a table and saved as ``grid.json`` and
``grid.csv`` where the traces go.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from cpg_actor.files import (
    atomic_write,
    atomic_write_text,
    check_path_given,
    refuse_linked_folders,
)
from cpg_actor.limits import brief
from cpg_actor.plots import GAIT_WINDOW, draw_gait_diagram, save_figure
from cpg_actor.robots.registry import all_metrics, all_simulators, get_robot

HELP = "evaluate a trained run deterministically; save per-step traces, figures (and a video)"
# the figures drawn next to the traces: for every run, and where the traces have what they
# need (the quadruped's); in a folder the user names, kept unless --overwrite, as the traces
CURVES_FIGURE = "training_curves.png"
TRACES_FIGURE = "traces.png"
GAIT_FIGURE = "gait_diagram.png"
SPEED_FIGURE = "forward_speed.png"
FIGURES = (CURVES_FIGURE, TRACES_FIGURE, GAIT_FIGURE, SPEED_FIGURE)
SPEED_SMOOTHING = 0.5  # s: the running mean drawn over the measured forward speed
GRID_FILES = ("grid.json", "grid.csv")  # --grid's table, where the traces go


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
        choices=all_simulators(),
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
    parser.add_argument("--video", default=None, help="write the first episode here: .mp4, or .gif "
                        "(at most 20 frames per second and 320 pixels wide)")  # fmt: skip
    parser.add_argument(
        "--output", default=None, help="traces file (default RUN_DIR/eval/traces.npz)"
    )
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="replace an existing --output (its figures) or --video; RUN_DIR/eval/'s traces and "
        "figures are always replaced",
    )
    parser.add_argument(
        "--grid",
        action="store_true",
        help="quadrupeds: the evaluation protocol instead: a fixed grid of velocity commands "
        "(forward, backward, lateral, turning, combined, standing), each held for an episode, "
        "plus payload and push checks; a table printed and saved as grid.json and grid.csv "
        "where the traces go (docs/quadruped.md, 'Evaluation protocol')",
    )
    parser.add_argument(
        "--grid-levels",
        type=int,
        nargs="+",
        default=None,
        metavar="LEVEL",
        help="with --grid: run it on flat ground and on rough ground at each of these "
        "difficulty levels (every kind of tile, the curriculum off; docs/quadruped.md, "
        "'Terrain'); default: on the run's ground as evaluated (flat, or --set env.terrain...)",
    )
    parser.add_argument(
        "--video-only",
        action="store_true",
        help="with --video: record the video only (a run already evaluated keeps its traces)",
    )


def run(args: argparse.Namespace) -> int:
    from cpg_actor.config import (
        MAX_EPISODES,
        TrainConfig,
        apply_dict,
        check_count,
        check_seed,
        parse_override,
    )
    from cpg_actor.deploy import load_policy
    from cpg_actor.robots.common.video import VIDEO_SUFFIXES
    from cpg_actor.training.evaluation import evaluate_policy, nominal_env

    check_seed(args.seed)
    for value, flag in ((args.run_dir, "RUN_DIR"), (args.checkpoint, "--checkpoint"),
                        (args.output, "--output"), (args.video, "--video")):  # fmt: skip
        check_path_given(value, flag)
    run_dir = Path(args.run_dir)
    config_path = run_dir / "config.yaml"
    if not config_path.is_file():
        raise FileNotFoundError(
            f"{config_path} does not exist; is {run_dir} a training run directory?"
        )
    check_count(args.episodes, "--episodes", MAX_EPISODES)
    checkpoint = Path(args.checkpoint) if args.checkpoint else run_dir / "checkpoints" / "last.pt"
    output = Path(args.output) if args.output else run_dir / "eval" / "traces.npz"
    if output.suffix != ".npz":
        raise ValueError(f"--output must end in .npz, got {output}")
    if args.output is None:  # the run's own folder, never one a link there leads to
        refuse_linked_folders(run_dir / "eval")
    if args.video_only and not args.video:
        raise ValueError("--video-only needs --video PATH")
    if args.grid_levels is not None and not args.grid:
        raise ValueError("--grid-levels needs --grid")
    if args.grid and args.video:
        raise ValueError("--grid writes a table, no video: run eval without --grid for --video")
    if args.video and Path(args.video).suffix.lower() not in VIDEO_SUFFIXES:  # before evaluating
        raise ValueError(f"--video must end in {' or '.join(VIDEO_SUFFIXES)}, got {args.video}")
    if not checkpoint.is_file():
        raise FileNotFoundError(f"checkpoint {checkpoint} does not exist")
    config = TrainConfig.load(config_path)
    nominal = nominal_env(config.env)
    if nominal is not config.env:
        config.env = nominal
        print("trained with env.randomize: evaluated on the nominal robot (--set "
              "env.randomize.NAME=[LOW,HIGH] evaluates with ranges)")  # fmt: skip
    if args.sim is not None:
        config.env = config.env.replace(**get_robot(config.robot).simulator_config(args.sim))
    for text in args.set:
        override = parse_override(text)
        if set(override) != {"env"}:
            raise ValueError(f"--set {brief(text)}: eval overrides env fields only (env.KEY=VALUE)")
        apply_dict(config, override, "")
    if args.set:
        config.validate()
    if args.grid:
        return run_grid(args, config, checkpoint, output)
    # the traces and figures in RUN_DIR/eval/ are eval's own derived data: a new evaluation
    # replaces them; a file the user named (--output, --video) needs --overwrite
    kept = [] if args.video_only or args.output is None else [
        output, *(output.parent / name for name in FIGURES)]  # fmt: skip
    for path in [*kept, *([Path(args.video)] if args.video else [])]:
        if path.exists() and not args.overwrite:
            raise FileExistsError(f"{path} exists; pass --overwrite to replace it")

    policy = load_policy(checkpoint, run_config=config)  # the run's agent, robot and env
    if args.video_only:
        record_video(policy, config, Path(args.video), args.seed, args.overwrite)
        print(f"video in {args.video}")
        return 0
    traces = evaluate_policy(policy, config, args.episodes, seed=args.seed)
    traces.update(physical_traces(traces))

    atomic_write(output, lambda f: np.savez(f, **traces))  # replaced whole or not at all
    for line in episode_lines(traces):
        print(line)
    print(f"traces in {output}")
    title = f"{run_dir.name}: {config.agent} on the {config.robot}"
    figures = plot_training_curves(
        run_dir / "metrics.jsonl", output.parent / CURVES_FIGURE, traces["metric_names"], title
    )
    figures += plot_traces(traces, output.parent / TRACES_FIGURE, title)
    figures += plot_gait(traces, output.parent / GAIT_FIGURE)  # [] where the env has no feet
    figures += plot_speed(traces, output.parent / SPEED_FIGURE)
    for figure in figures:
        print(f"figure {figure}")
    if args.video:
        record_video(policy, config, Path(args.video), args.seed, args.overwrite)
        print(f"video in {args.video}")
    return 0


def run_grid(args: argparse.Namespace, config, checkpoint: Path, output: Path) -> int:
    """``--grid``: the evaluation protocol on the run's policy, its table printed and saved as
    :data:`GRID_FILES` in ``output``'s folder (RUN_DIR/eval/'s replaced; a folder the user
    named keeps its files unless --overwrite)."""
    from cpg_actor.deploy import load_policy
    from cpg_actor.robustness import protocol

    robot = get_robot(config.robot)
    protocol.check_grid_robot(robot.name, config.env)
    paths = [output.parent / name for name in GRID_FILES]
    if args.output is not None:
        for path in paths:
            if path.exists() and not args.overwrite:
                raise FileExistsError(f"{path} exists; pass --overwrite to replace it")
    untrained = protocol.untrained_commands(config.env)
    if untrained:
        print(f"note: the run was trained without {', '.join(untrained)} (its command ranges); "
              "those rows are marked *")  # fmt: skip
    grounds: list[dict] = [{}]
    if args.grid_levels is not None:
        if not hasattr(config.env, "terrain"):
            raise ValueError(f"--grid-levels: the {robot.name} has no terrain")
        grounds = [protocol.flat_ground(config.env)]
        for level in args.grid_levels:  # each checked before anything runs
            ground = protocol.terrain_level(config.env, level)
            config.env.replace(**ground)
            grounds.append(ground)
    policy = load_policy(checkpoint, run_config=config)
    checks = len(protocol.checks(1.0, config.env.episode_seconds))
    print(f"evaluation protocol: {len(protocol.GRID)} commands and {checks} checks, "
          f"{args.episodes} episode(s) each")  # fmt: skip
    result = protocol.run_grid(policy, config, robot, args.episodes, args.seed, grounds)
    result.update(run=str(Path(args.run_dir)), checkpoint=str(checkpoint), agent=config.agent,
                  robot=robot.name)  # fmt: skip
    for line in protocol.table_lines(result):
        print(line)
    texts = (protocol.json_text(result), protocol.csv_text(result))
    for path, text in zip(paths, texts, strict=True):
        atomic_write_text(text, path)
        print(f"table in {path}")
    return 0


def physical_traces(traces: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The physical metrics (:mod:`cpg_actor.metrics.physical`) of every episode the
    traces define them for, saved with the traces: ``physical_NAME`` ``(E,)`` each, their
    names in ``physical_names``."""
    from cpg_actor.metrics.physical import episode_metrics

    values = episode_metrics(traces)
    out = {f"physical_{name}": value for name, value in values.items()}
    out["physical_names"] = np.array(list(values), dtype=str)
    return out


def physical_line(traces: dict[str, np.ndarray]) -> str | None:
    """The physical metrics' means over the episodes that define them, with their units, as
    one printed line (docs/reproduction.md: their definitions); None where the traces have none."""
    from cpg_actor.metrics.physical import METRICS
    from cpg_actor.training.evaluation import finite_mean

    names = [str(name) for name in traces.get("physical_names", ())]
    if not names:
        return None

    def text(name: str) -> str:
        value = finite_mean(traces[f"physical_{name}"])
        info = METRICS[name]
        if not np.isfinite(value):
            return f"{info.label} —"
        if not info.unit:
            return f"{info.label} {100 * value:.1f}%"
        return f"{info.label} {value:.4g} {info.unit}"

    return "physical (mean over episodes): " + ", ".join(text(name) for name in names)


def episode_lines(traces: dict[str, np.ndarray]) -> list[str]:
    """The printed result of an evaluation: a line per episode (return, the env's metrics,
    steps), the means, and a footnote where a metric was undefined (NaN) for an episode: it
    prints as "—" and the mean is over the episodes that define it (how many is said)."""
    from cpg_actor.training.evaluation import finite_mean

    names = [str(name) for name in traces["metric_names"]]  # the env's (hop_height)
    episodes = len(traces["episode_return"])

    def value(x: float) -> str:
        return f"{x:.3f}" if np.isfinite(x) else "—"

    lines = []
    for i in range(episodes):
        metrics = ", ".join(f"{name} {value(traces[name][i])}" for name in names)
        lines.append(f"episode {i}: return {traces['episode_return'][i]:.3f}, "
                     f"{metrics + ', ' if metrics else ''}{traces['length'][i]} steps")  # fmt: skip
    means, undefined = [], []
    for name in names:
        defined = int(np.isfinite(np.asarray(traces[name], dtype=float)).sum())
        text = f"mean {name} {value(finite_mean(traces[name]))}"
        if defined < episodes:
            text += f" (over the {defined} of {episodes} episodes that define it)"
            undefined.append(name)
        means.append(text)
    lines.append(", ".join([f"mean return {traces['episode_return'].mean():.3f}", *means])
                 + f" over {episodes} episodes")  # fmt: skip
    physical = physical_line(traces)
    if physical is not None:
        lines.append(physical)
    for name in undefined:
        info = all_metrics().get(name)
        reason = info.undefined if info is not None else ""
        where = f" where {reason}" if reason else ""
        lines.append(f"—: {name} is undefined for an episode{where}; the mean leaves it out")
    return lines


def record_video(policy, config, path: Path, seed: int, overwrite: bool) -> None:
    """One deterministic episode in the agent's own environment (one env), rendered offscreen
    by its ``render_frame`` (the hopper's or the quadruped's scene) and encoded as it runs;
    a GIF renders only the frames it keeps."""
    from cpg_actor.robots.common.video import frame_stride, write_video
    from cpg_actor.robots.registry import get_robot
    from cpg_actor.training.build import make_env

    env = make_env(config, get_robot(config.robot), 1, 1)
    fps = round(1.0 / config.env.control_dt)
    stride = frame_stride(path, fps)

    def frames():
        obs, _ = env.reset(seed=seed)
        policy.reset(1)
        yield env.render_frame(0)
        for step in range(1, config.env.episode_steps + 1):
            obs, _, terminated, truncated, _ = env.step(policy.act(obs).action)
            if terminated[0] or truncated[0]:
                break  # the env has already reset: the frame would show the next episode
            if step % stride == 0:
                yield env.render_frame(0)

    try:
        write_video(frames(), path, fps=fps / stride, overwrite=overwrite)
    finally:
        env.close()


def plot_training_curves(
    metrics: Path, path: Path, metric_names=(), title: str | None = None
) -> list[Path]:
    """The run's learning curves from ``metrics.jsonl`` (:func:`training_curves_figure`);
    nothing where the run has no metrics file."""
    from cpg_actor.inputs import read_jsonl

    if not metrics.is_file():
        return []
    rows = read_jsonl(metrics, "the metrics cpg-actor train logs")
    names = [str(name) for name in metric_names]
    fig = training_curves_figure(rows, names, title or metrics.parent.name)
    save_figure(fig, path, dpi=120)
    return [path]


def training_curves_figure(rows: list[dict], metric_names=(), title: str = ""):
    """A panel per quantity the run logged against training steps: the episode return, then
    each of the env's episode metrics (``metric_names``: the hopper's hop height, the
    quadruped's speed error, forward speed, ...; without names, every ``eval/`` metric of the
    env), each from the training episodes (``charts/NAME``) and the deterministic evaluations
    (``eval/NAME``) where logged. A quantity never logged gets no panel."""
    from matplotlib.figure import Figure

    from cpg_actor.plots import metric_label
    from cpg_actor.training.progress import NOT_ENV_METRICS

    names = list(metric_names) or sorted(
        {key.removeprefix("eval/") for row in rows for key in row if key.startswith("eval/")}
        - set(NOT_ENV_METRICS)
    )
    order = list(all_metrics())  # the known metrics in the robots' order (each's headline first)
    names.sort(key=lambda name: (order.index(name) if name in order else len(order), name))
    steps = np.array([row.get("global_step", np.nan) for row in rows], dtype=float)

    def series(key: str) -> tuple[np.ndarray, np.ndarray]:
        values = np.array([np.nan if row.get(key) is None else row[key] for row in rows],
                          dtype=float)  # fmt: skip
        kept = np.isfinite(values) & np.isfinite(steps)
        return steps[kept], values[kept]

    panels = []  # (label, training series, evaluation series)
    for label, training, evaluation in (
        ("episode return", "charts/episode_return", "eval/return"),
        *((metric_label(name), f"charts/{name}", f"eval/{name}") for name in names),
    ):
        curves = series(training), series(evaluation)
        if any(len(x) for x, _ in curves):
            panels.append((label, *curves))
    columns = min(4, max(1, len(panels)))
    rows_of_panels = -(-max(1, len(panels)) // columns)
    fig = Figure(figsize=(3.6 * columns + 0.6, 2.9 * rows_of_panels + 0.8), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows_of_panels, columns, squeeze=False)).ravel()
    for axis in axes[len(panels) :]:
        axis.set_visible(False)
    if not panels:
        axes[0].set_visible(True)
        axes[0].text(0.5, 0.5, "no finished episode and no evaluation logged yet",
                     ha="center", va="center", transform=axes[0].transAxes)  # fmt: skip
        axes[0].set_axis_off()
    for axis, (label, training, evaluation) in zip(axes, panels, strict=False):
        if len(training[0]):
            axis.plot(*training, color="tab:blue", label="training episodes (exploring)")
        if len(evaluation[0]):
            axis.plot(*evaluation, "o-", color="tab:orange", ms=3,
                      label="deterministic evaluation")  # fmt: skip
        axis.set_title(label, fontsize="medium")  # the quantity and its unit
        axis.set_xlabel("control steps")
        axis.grid(alpha=0.3)
    legend: dict[str, object] = {}  # every panel's lines by label
    for axis in axes:
        for handle, name in zip(*axis.get_legend_handles_labels(), strict=True):
            legend.setdefault(name, handle)
    if legend:  # one legend for the figure, under the panels: none covers data
        fig.legend(list(legend.values()), list(legend), loc="outside lower center",
                   ncols=len(legend), fontsize="small")  # fmt: skip
    fig.suptitle(f"{title}: training curves" if title else "training curves")
    return fig


TRACE_WHOLE_EPISODE = 5.0  # s: an episode up to this long is shown whole in traces.png
TRACE_WINDOW = GAIT_WINDOW  # s: the last seconds of a longer one (the gait diagram's too)


def _joint_groups(joints: list[str]) -> dict[str, list[int]]:
    """Joints by the limb their name starts with (``LF_HFE``: ``LF``), in order; one group
    ``""`` for a robot whose joint names have no limb prefix (the hopper's HFE, KFE)."""
    groups: dict[str, list[int]] = {}
    for index, joint in enumerate(joints):
        groups.setdefault(joint.rsplit("_", 1)[0] if "_" in joint else "", []).append(index)
    return groups


def _short(name: str, group: str) -> str:
    return name.removeprefix(f"{group}_") if group else name


def _oscillator_groups(traces, joints, groups) -> dict[str, list[tuple[int, str]]]:
    """The CPG's oscillators by limb (as :func:`_joint_groups`), with their names: the saved
    ``oscillator_names``, else the joints' (one oscillator per joint), else the limbs' (one
    per limb), else ``osc i``."""
    count = traces["theta_dot"].shape[-1]
    if "oscillator_names" in traces:
        names = [str(name) for name in traces["oscillator_names"]]
    elif count == len(joints):
        names = list(joints)
    elif count == len(groups):
        names = list(groups)
    else:
        names = [f"osc {i}" for i in range(count)]
    placed: dict[str, list[tuple[int, str]]] = {group: [] for group in groups}
    for index, name in enumerate(names):
        group = next((g for g in groups if g and (name == g or name.startswith(f"{g}_"))), None)
        if group is None:
            group = next(iter(groups)) if len(groups) == 1 else ""
        placed.setdefault(group, []).append((index, name))
    return placed


def plot_traces(traces: dict[str, np.ndarray], path: Path, title: str = "") -> list[Path]:
    """Episode 0's traces (:func:`traces_figure`) as ``path``."""
    save_figure(traces_figure(traces, title), path)
    return [path]


def traces_figure(traces: dict[str, np.ndarray], title: str = ""):
    """Episode 0 (paper Fig. 6-7): desired (solid) vs measured (dashed) joint positions and
    velocities, with the motor's speed limit (``velocity_limit``) dashed on the velocities; a
    CPG's phase velocity and amplitude acceleration; the hip and foot heights where the robot
    has them. An episode up to ``TRACE_WHOLE_EPISODE`` s is shown whole, a longer one its last
    ``TRACE_WINDOW`` s. A column per limb (the quadruped's legs), its joints in one colour
    each."""
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    from cpg_actor.plots import draw_velocity_limits

    length = int(traces["length"][0])
    time = _episode(traces, "time")
    dt = float(traces["control_dt"]) if "control_dt" in traces else float(time[1] - time[0])
    duration = length * dt
    shown = slice(None) if duration <= TRACE_WHOLE_EPISODE else slice(
        max(0, length - round(TRACE_WINDOW / dt)), None)  # fmt: skip
    time = time[shown]
    # the robot's joints (traces saved before joint names were: the hopper's two)
    joints = [str(j) for j in traces.get("joint_names", ("HFE", "KFE"))]
    groups = _joint_groups(joints)
    kinds = list(dict.fromkeys(_short(joints[i], g) for g, idx in groups.items() for i in idx))
    colour = {kind: f"C{k}" for k, kind in enumerate(kinds)}
    # each joint's speed limit (one number for all, or one per joint of a leg, repeated)
    joint_limits = (np.resize(np.atleast_1d(traces["velocity_limit"]).astype(float), len(joints))
                    if "velocity_limit" in traces else None)  # fmt: skip

    def episode(key: str) -> np.ndarray:
        return _episode(traces, key)[shown]

    rows = []  # (axis label, draw(axis, group), the line styles to explain)

    def joint_row(desired: str, measured: str, label: str, limits: bool) -> None:
        if desired not in traces:
            return

        def draw(axis, group: str) -> None:
            for i in groups[group]:
                kind = _short(joints[i], group)
                axis.plot(time, episode(desired)[:, i], color=colour[kind], lw=1.3, label=kind)
                if measured in traces:
                    axis.plot(time, episode(measured)[:, i], "--", color=colour[kind], lw=1.0)
            if limits and joint_limits is not None:
                for limit in sorted({float(joint_limits[i]) for i in groups[group]}):
                    draw_velocity_limits(axis, limit)

        rows.append((label, draw, measured in traces))

    joint_row("desired_position", "measured_position", "joint position (rad)", False)
    joint_row("desired_velocity", "measured_velocity", "joint velocity (rad/s)", True)
    oscillators = _oscillator_groups(traces, joints, groups) if "theta_dot" in traces else {}
    for key, label in (("theta_dot", "oscillator phase\nvelocity $\\dot\\theta$ (rad/s)"),
                       ("r_ddot", "oscillator amplitude\nacceleration $\\ddot r$ (rad/s$^2$)"),
                       ):  # fmt: skip
        if key not in traces:
            continue

        def draw(axis, group: str, key=key) -> None:
            for index, name in oscillators.get(group, []):
                kind = _short(name, group) if name != group else "leg oscillator"
                axis.plot(time, episode(key)[:, index], color=colour.get(kind, "0.3"),
                          label=kind)  # fmt: skip

        rows.append((label, draw, False))
    if "hip_height" in traces:

        def heights(axis, group: str) -> None:
            axis.plot(time, episode("hip_height"), color="C4", label="hip")
            axis.plot(time, episode("foot_height"), ":", color="C5", label="foot")

        rows.append(("height (m)", heights, False))

    columns = list(groups)
    fig = Figure(figsize=(2.6 + 3.4 * len(columns) if len(columns) > 1 else 11.0,
                          1.9 * len(rows) + 1.0), layout="constrained")  # fmt: skip
    axes = np.asarray(fig.subplots(len(rows), len(columns), sharex=True, sharey="row",
                                   squeeze=False))  # fmt: skip
    for r, (label, draw, styles) in enumerate(rows):
        legend: dict[str, object] = {}  # the row's lines by label, over its columns
        for c, group in enumerate(columns):
            axis = axes[r, c]
            draw(axis, group)
            axis.grid(alpha=0.3)
            if r == 0 and group:
                axis.set_title(group)
            for handle, name in zip(*axis.get_legend_handles_labels(), strict=True):
                legend.setdefault(name, handle)
        axes[r, 0].set_ylabel(label)
        if styles:  # what solid and dashed mean
            legend["desired (sent)"] = Line2D([], [], color="0.3")
            legend["measured"] = Line2D([], [], color="0.3", ls="--")
        # outside the last column: no data covered
        axes[r, -1].legend(list(legend.values()), list(legend), fontsize=7, loc="upper left",
                           bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)  # fmt: skip
    for axis in axes[-1]:
        axis.set_xlabel("time (s)")
    window = (f"whole episode ({duration:g} s)" if shown == slice(None)
              else f"last {time[-1] - time[0] + dt:g} s of {duration:g} s")  # fmt: skip
    fig.suptitle(f"{title + ': ' if title else ''}evaluation episode 0, {window}")
    return fig


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
    shown = min(GAIT_WINDOW, len(contact) * dt)
    axis.set_title(f"Foot contacts, episode 0, last {shown:g} s of {len(contact) * dt:g} s: "
                   f"duty factor {duty}", fontsize="medium", loc="left")  # fmt: skip
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
    fig = Figure(figsize=(11.0, 3.6), layout="constrained")
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
    # outside the axes: no data covered
    axis.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    axis.set_title("Commanded vs measured forward speed, every episode (episode 0 raw, faint)",
                   fontsize="medium", loc="left")  # fmt: skip
    save_figure(fig, path)
    return [path]
