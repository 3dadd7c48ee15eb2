"""The paper's figures from a results directory (matplotlib Agg; PNG and PDF).

File names are the paper's LaTeX labels without ``fig:``. Every function takes the loaded
:class:`~cpg_actor_studies.reproduction.results.Results` and the figure directory and returns
``(written paths, notes)``; a variant that was not run (or has no eval traces) is left out of
a figure with a note, and a figure with nothing to show is not written.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from cpg_actor.api import color, label, step_axis, step_labels, steps_text
from cpg_actor_studies.hopper_paper.claims import VELOCITY_LIMIT
from cpg_actor_studies.reproduction.results import Results, Run, sent_velocity

JOINTS = ("HFE", "KFE")
TRACE_WINDOW_S = 3.0  # seconds of an episode shown in the trace figures
MAX_HISTORY = 8  # checkpoints drawn in the parameter-distribution figures
FORMATS = ("png", "pdf")

Output = tuple[list[Path], list[str]]


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, directory: Path, name: str) -> list[Path]:
    from cpg_actor.api import save_figure

    paths = [save_figure(fig, directory / f"{name}.{ext}", dpi=130 if ext == "png" else None)
             for ext in FORMATS]  # fmt: skip
    _plt().close(fig)
    return paths


# -- fig:ep_reward ------------------------------------------------------------------------------
def ep_reward(results: Results, directory: Path) -> Output:
    """Mean episode return against steps: mean over seeds, min-max band, one line per variant."""
    plt = _plt()
    notes: list[str] = []
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    drawn: list[tuple[str, np.ndarray, np.ndarray, int]] = []  # variant, grid, curves, count
    for variant in results.variants:
        runs = results.runs.get(variant)
        if not runs:
            notes.append(f"ep_reward: {variant} was not run")
            continue
        curves = [run.return_curve() for run in runs]
        curves = [(s, v) for s, v in curves if np.isfinite(v).any()]
        if not curves:
            notes.append(f"ep_reward: {variant} has no finished episodes logged")
            continue
        end = min(s[np.isfinite(v)].max() for s, v in curves)
        start = max(s[np.isfinite(v)].min() for s, v in curves)
        grid = np.linspace(start, end, 200) if end > start else np.array([end])
        stacked = np.stack(
            [np.interp(grid, s[np.isfinite(v)], v[np.isfinite(v)]) for s, v in curves]
        )
        drawn.append((variant, grid, stacked, len(curves)))
    if not drawn:
        plt.close(fig)
        return [], notes + ["ep_reward: nothing to draw"]
    scale, xlabel = step_axis(max(grid.max() for _, grid, _, _ in drawn), "time steps")
    for variant, grid, stacked, count in drawn:
        x = grid / scale
        mean = stacked.mean(axis=0)
        ax.plot(x, mean, color=color(variant), label=f"{label(variant)} (n={count})")
        if count > 1:
            ax.fill_between(
                x, stacked.min(axis=0), stacked.max(axis=0), color=color(variant), alpha=0.2
            )
    ax.set_xlabel(xlabel)
    ax.set_ylabel("mean episode return")
    ax.set_title("Episode reward (mean over seeds, band: min-max)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, directory, "ep_reward"), notes


# -- fig:cpg_output, fig:cpg_theta_dot, fig:cpg_r_dot_dot ------------------------------------------
CPG_VARIANTS = ("cho2019", "cho2019-warm", "cho2019-paper", "cpg-actor-open-loop", "open-loop-es",
                "cpg-actor-paper", "cpg-actor")  # fmt: skip


def _final_traces(
    results: Results, variants: tuple[str, ...], key: str, name: str
) -> tuple[list[tuple[str, Run, dict]], list[str]]:
    """(variant, run, traces) of the lowest seed's final evaluation, for runs whose traces hold
    ``key`` with one value per joint; notes for the others that were asked for."""
    found, notes = [], []
    for variant in variants:
        if variant not in results.variants:  # neither asked for nor found: nothing to note
            continue
        run = results.first(variant)
        if run is None:
            notes.append(f"{name}: {variant} was not run")
            continue
        traces = run.traces()
        if traces is None:
            notes.append(f"{name}: {variant} seed {run.seed} has no eval traces")
            continue
        if key == "desired_velocity":  # every agent's: the finite difference of what was sent
            velocity = sent_velocity(traces)
            traces = {k: v for k, v in traces.items() if k != key}
            if velocity is not None:
                traces[key] = velocity
        if key not in traces or traces[key].ndim != 3 or traces[key].shape[-1] != len(JOINTS):
            notes.append(f"{name}: {variant} traces have no per-joint '{key}'")
            continue
        found.append((variant, run, traces))
    return found, notes


def _joint_panels(
    results: Results,
    directory: Path,
    variants: tuple[str, ...],
    key: str,
    name: str,
    ylabel: str,
    title: str,
    limit_lines: float | None = None,
) -> Output:
    plt = _plt()
    found, notes = _final_traces(results, variants, key, name)
    if not found:
        return [], notes + [f"{name}: nothing to draw"]
    fig, axes = plt.subplots(len(JOINTS), 1, figsize=(7.0, 4.8), sharex=True)
    for variant, _run, traces in found:
        t = traces["time"]
        window = t <= t[0] + TRACE_WINDOW_S
        for j, ax in enumerate(axes):
            ax.plot(
                t[window], traces[key][window, 0, j], color=color(variant), label=label(variant)
            )
    for j, ax in enumerate(axes):
        if limit_lines is not None:
            for sign in (-1, 1):
                ax.axhline(sign * limit_lines, color="red", lw=1.0, ls="--")
        ax.set_ylabel(f"{JOINTS[j]} {ylabel}")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, loc="upper right")
    axes[0].set_title(f"{title} (seed {found[0][1].seed}, final checkpoint, episode 0)")
    axes[-1].set_xlabel("time (s)")
    fig.tight_layout()
    return _save(fig, directory, name), notes


def directory_of(results: Results) -> Path:
    return results.out / "figures"


def _panel_figures(
    results: Results,
    directory: Path,
    variants: tuple[str, ...],
    panels: tuple[tuple[str, str, str, str, float | None], ...],
) -> Output:
    """One :func:`_joint_panels` figure per ``(key, name, ylabel, title, limit_lines)``."""
    paths: list[Path] = []
    notes: list[str] = []
    for key, name, ylabel, title, limit in panels:
        written, more = _joint_panels(results, directory, variants, key, name, ylabel, title, limit)
        paths += written
        notes += more
    return paths, notes


# (trace key, figure, y label, title, no limit lines)
CPG_PANELS = (
    ("desired_position", "cpg_output", "desired position (rad)", "Desired positions", None),
    ("theta_dot", "cpg_theta_dot", "theta_dot (rad/s)", "Phase velocity theta_dot (eq. 1)", None),
    ("r_ddot", "cpg_r_dot_dot", "r_ddot (rad/s^2)", "Amplitude acceleration r_ddot (eq. 1)", None),
)


def cpg_traces(results: Results, directory: Path) -> Output:
    """The CPG agents' desired positions, phase velocities and amplitude accelerations over the
    first seconds of an evaluation episode, one figure each (:data:`CPG_PANELS`)."""
    return _panel_figures(results, directory, CPG_VARIANTS, CPG_PANELS)


# -- fig:des_output (des_pos, des_vel) ---------------------------------------------------------
def des_output(results: Results, directory: Path) -> Output:
    """Desired positions and velocities of the MLP actor vs the CPG-Actor, lines at +- the
    motor's speed limit (the runs' ``env.velocity_limit``, else 15 rad/s);
    the velocities of both the finite difference of the desired positions sent."""
    variants = ("mlp", "cpg-actor")
    # the motor's speed limit the runs were trained with (their env config), else the paper's
    runs = [run for run in map(results.first, variants) if run is not None]
    velocity_limit = next((float(run.config["env"]["velocity_limit"]) for run in runs
                           if "velocity_limit" in (run.config.get("env") or {})),
                          VELOCITY_LIMIT)  # fmt: skip
    return _panel_figures(results, directory, variants, (
        ("desired_position", "des_pos", "desired position (rad)", "Desired positions", None),
        ("desired_velocity", "des_vel", "desired velocity (rad/s)",
         "Desired velocities (red: motor limits)", velocity_limit),
    ))  # fmt: skip


# -- fig:parameters_under_training ----------------------------------------------------------------
def _kde(values: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Gaussian kernel density estimate with Silverman's bandwidth (numpy only)."""
    values = values[np.isfinite(values)]
    std = values.std() if values.size > 1 else 0.0
    span = grid[-1] - grid[0]
    bandwidth = max(1.06 * std * values.size ** (-1 / 5), 0.02 * span, 1e-9)
    z = (grid[:, None] - values[None, :]) / bandwidth
    return np.exp(-0.5 * z**2).sum(axis=1) / (values.size * bandwidth * np.sqrt(2 * np.pi))


def _history(run: Run, keys: tuple[str, ...]) -> list[tuple[int, int, dict[str, np.ndarray]]]:
    """``[(iteration, global_step, {key: values})]`` for up to ``MAX_HISTORY`` checkpoints,
    evenly spread over the run."""
    from cpg_actor.api import load_checkpoint

    checkpoints = run.checkpoints()
    iterations = sorted(checkpoints)
    if len(iterations) > MAX_HISTORY:
        picks = np.unique(np.round(np.linspace(0, len(iterations) - 1, MAX_HISTORY)).astype(int))
        iterations = [iterations[i] for i in picks]
    history = []
    for iteration in iterations:
        data = load_checkpoint(checkpoints[iteration])
        state = data["agent_state"]
        values = {k: state[k].detach().cpu().numpy().ravel() for k in keys if k in state}
        history.append((iteration, int(data["global_step"]), values))
    return history


PARAMETER_PANELS = (
    (
        "cpg_param_training",
        "cpg.parametrisation.vector",
        "CPG parameters: change of vector V since the start",
    ),
    ("mlp_weight_feedback", "feedback.4.weight", "feedback MLP output-layer weights"),
    ("mlp_bias_feedback", "feedback.4.bias", "feedback MLP output-layer biases"),
)


def _feedback_keys(run: Run) -> dict[str, str]:
    """The state_dict keys of the feedback MLP's last linear layer (``feedback.K.weight``)."""
    from cpg_actor.api import load_checkpoint

    checkpoints = run.checkpoints()
    if not checkpoints:
        return {}
    state = load_checkpoint(checkpoints[max(checkpoints)])["agent_state"]
    layers = sorted(
        {int(k.split(".")[1]) for k in state if k.startswith("feedback.") and k.endswith("weight")}
    )
    if not layers:
        return {}
    return {"weight": f"feedback.{layers[-1]}.weight", "bias": f"feedback.{layers[-1]}.bias"}


def parameters_under_training(results: Results, directory: Path) -> Output:
    """Distributions of the CPG vector V and of the feedback MLP's output layer at checkpoints
    spread over training, dark (early) to light (late); from the lowest seed of cpg-actor
    (the CPG panel falls back to cpg-actor-open-loop)."""
    plt = _plt()
    notes: list[str] = []
    run = results.first("cpg-actor")
    feedback: dict[str, str] = {}
    if run is None:
        notes.append("parameters_under_training: cpg-actor was not run")
        run = results.first("cpg-actor-open-loop")
        if run is None:
            return [], notes + ["parameters_under_training: no CPG-Actor run, nothing to draw"]
        notes.append("parameters_under_training: CPG panel from cpg-actor-open-loop, no feedback")
    else:
        feedback = _feedback_keys(run)
    panels = [
        (
            name,
            {"weight": feedback.get("weight"), "bias": feedback.get("bias")}.get(kind, key),
            title,
        )
        for (name, key, title), kind in zip(
            PARAMETER_PANELS, ("cpg", "weight", "bias"), strict=True
        )
    ]
    panels = [(name, key, title) for name, key, title in panels if key]
    history = _history(run, tuple(key for _, key, _ in panels))
    if not history:
        return [], notes + ["parameters_under_training: the run has no checkpoints"]
    # the 8 entries of V live on different scales (Hz, rad, 1/s, ...): their distribution hardly
    # moves, so the CPG panel shows the change of each entry since the first checkpoint
    cpg_key = PARAMETER_PANELS[0][1]
    start = history[0][2].get(cpg_key)
    if start is not None:
        for _, _, values in history:
            if cpg_key in values:
                values[cpg_key] = values[cpg_key] - start
    cmap = plt.get_cmap("viridis")
    paths: list[Path] = []

    def draw(ax, key: str, title: str) -> None:
        stacks = [values[key] for _, _, values in history if key in values]
        low = min(v.min() for v in stacks)
        high = max(v.max() for v in stacks)
        pad = 0.1 * (high - low) + 1e-3
        grid = np.linspace(low - pad, high + pad, 300)
        for i, (_, step, values) in enumerate(history):
            shade = cmap(i / max(1, len(history) - 1))
            density = _kde(values[key], grid)
            ax.plot(grid, density, color=shade, lw=1.2, label=steps_text(step))
            ax.fill_between(grid, density, color=shade, alpha=0.08)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("value")
        ax.set_ylabel("density")
        ax.grid(alpha=0.3)

    fig, axes = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 3.6), squeeze=False)
    for ax, (_, key, title) in zip(axes[0], panels, strict=True):
        draw(ax, key, title)
    axes[0][-1].legend(title="steps", fontsize=7, title_fontsize=7)
    fig.suptitle(f"{label(run.variant)} seed {run.seed}: parameters over training (dark to light)")
    fig.tight_layout()
    paths += _save(fig, directory, "parameters_under_training")
    for name, key, title in panels:
        fig, ax = plt.subplots(figsize=(4.6, 3.6))
        draw(ax, key, title)
        ax.legend(title="steps", fontsize=7, title_fontsize=7)
        fig.tight_layout()
        paths += _save(fig, directory, name)
    return paths, notes


# -- fig:cpg_actor_training_over_time -------------------------------------------------------------
def cpg_actor_training_over_time(results: Results, directory: Path) -> Output:
    """Hip (solid) and foot (dotted) height, and desired HFE / KFE positions, at each stage of
    training (lowest cpg-actor seed, eval episode 0)."""
    plt = _plt()
    name = "cpg_actor_training_over_time"
    run = results.first("cpg-actor")
    if run is None:
        return [], [f"{name}: cpg-actor was not run"]
    stages = []
    for k, stage in enumerate(run.stages):
        traces = run.traces(k)
        if traces is not None:
            stages.append((stage, traces))
    if not stages:
        return [], [f"{name}: cpg-actor seed {run.seed} has no stage evaluations"]
    # stages evaluated at one checkpoint (a budget too short for them) are one snapshot: drawn
    # once, so that each line is a different policy with a label of its own
    stages = list({stage["iteration"]: (stage, traces) for stage, traces in stages}.values())
    steps = [steps_at_iteration(run, stage["iteration"]) for stage, _ in stages]
    logged = all(count is not None for count in steps)
    counts = steps if logged else [stage["iteration"] for stage, _ in stages]
    texts = step_labels(counts) if logged else [str(count) for count in counts]
    names = [f"{text} steps" if logged else f"iteration {text}" for text in texts]
    labels = {stage["iteration"]: name for (stage, _), name in zip(stages, names, strict=True)}
    snapshots = f"{', '.join(texts)} {'training steps' if logged else 'iterations'}"
    cmap = plt.get_cmap("viridis")
    robot = run.config.get("robot", "hopper")
    joints = _named_joints(stages[0][1])

    def stage_label(stage: dict) -> str:
        return labels[stage["iteration"]]

    def shaded():
        """Each stage's traces, its shade and the time and mask of the window drawn."""
        for i, (stage, traces) in enumerate(stages):
            t = traces["time"]
            shade = cmap(i / max(1, len(stages) - 1) * 0.85)
            yield stage, traces, shade, t, t <= t[0] + TRACE_WINDOW_S

    def draw_heights(ax) -> None:
        if "hip_height" not in stages[0][1]:
            ax.text(0.5, 0.5, f"the {robot}'s traces have no hip height", ha="center",
                    transform=ax.transAxes)  # fmt: skip
            return
        for stage, traces, shade, t, window in shaded():
            ax.plot(
                t[window],
                traces["hip_height"][window, 0],
                color=shade,
                label=f"hip, {stage_label(stage)}",
            )
            ax.plot(t[window], traces["foot_height"][window, 0], ":", color=shade)
        ax.set_ylabel("height (m); hip solid, foot dotted")
        ax.set_title(f"The {robot}'s hip and foot height at each snapshot", fontsize=9)

    def draw_joint(ax, j: int) -> None:
        if j >= len(joints):
            return
        index, joint = joints[j]
        for stage, traces, shade, t, window in shaded():
            ax.plot(
                t[window],
                traces["desired_position"][window, 0, index],
                color=shade,
                label=stage_label(stage),
            )
        ax.set_ylabel(f"desired {joint} position (rad)")
        ax.set_title(f"Desired {joint} position at each snapshot", fontsize=9)

    drawers: list[tuple[str, Callable]] = [
        ("hopper_hip_foot_pos", draw_heights),
        ("hfe_during_training", lambda ax: draw_joint(ax, 0)),
        ("kfe_during_training", lambda ax: draw_joint(ax, 1)),
    ]
    paths: list[Path] = []
    fig, axes = plt.subplots(1, 3, figsize=(14, 3.8))
    for ax, (_, drawer) in zip(axes, drawers, strict=True):
        drawer(ax)
        ax.set_xlabel("time (s)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    fig.suptitle(f"CPG-Actor seed {run.seed} on the {robot}: eval episode 0 after {snapshots}")
    fig.tight_layout()
    paths += _save(fig, directory, name)
    for sub, drawer in drawers:
        fig, ax = plt.subplots(figsize=(5.0, 3.8))
        drawer(ax)
        ax.set_xlabel("time (s)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
        fig.tight_layout()
        paths += _save(fig, directory, sub)
    return paths, []


def _named_joints(traces: dict) -> list[tuple[int, str]]:
    """``(column, name)`` of the joints ``JOINTS`` names in the traces: the hopper's HFE and
    KFE, a legged robot's first leg's (``LF_HFE``, ``LF_KFE``)."""
    names = [str(j) for j in traces.get("joint_names", JOINTS)]
    found = []
    for joint in JOINTS:
        index = next((i for i, n in enumerate(names) if n == joint or n.endswith(f"_{joint}")),
                     None)  # fmt: skip
        if index is not None:
            found.append((index, names[index]))
    return found


def steps_at_iteration(run: Run, iteration: int) -> int | None:
    """The env steps a run had taken at the end of ``iteration``, as logged: a start gait's
    search steps included when the run is charged with them (``search_steps``); None when the
    run logged no row for that iteration."""
    for row in run.metrics:
        if row.get("iteration") == iteration and "global_step" in row:
            return int(row["global_step"])
    return None


FIGURES: tuple[Callable[[Results, Path], Output], ...] = (
    ep_reward,
    cpg_traces,
    parameters_under_training,
    des_output,
    cpg_actor_training_over_time,
)


def make_figures(results: Results) -> Output:
    """Every figure into ``OUT/figures``; a failing figure becomes a note, not an exception."""
    directory = directory_of(results)
    paths: list[Path] = []
    notes: list[str] = []
    for figure in FIGURES:
        try:
            written, more = figure(results, directory)
        except Exception as error:  # one broken figure must not lose the report
            written, more = [], [f"{figure.__name__}: failed ({error!r})"]
        paths += written
        notes += more
    return paths, notes
