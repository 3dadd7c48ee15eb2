"""The quadrupeds' evaluation protocol (``cpg-actor eval RUN --grid``; docs/quadruped.md,
"Evaluation protocol"): a fixed grid of velocity commands, each held for a whole episode, and
the protocol's payload and push checks, every agent measured the same way.

Why a fixed grid: the omnidirectional task draws its commands at random, so an evaluation of
it measures a mixture that changes with the seed and the ranges. The grid asks the same
questions of every policy: walk forward and backward slowly and fast, side-step left and
right, turn on the spot both ways, a combined command and standing still (the field's
ranges: vx to 1 m/s, vy to 0.5, yaw to 1 rad/s). Each command is a point range of the run's
env config with no resampling and no standing draws, so the env's own episode metrics are
the protocol's (:mod:`cpg_actor.tasks.velocity`): linear velocity error and yaw-rate error
(means over the episode of the per-step errors, start-up included: what the tracking reward
sees) and their offsets (the errors of the episode's mean velocity: the gait's sway within a
stride averaged out, which a trot's yaw rocking otherwise dominates), falls, the planar
cost of transport (for the commands that ask the base to travel: turning on the spot or
standing has no distance to divide by, only drift), foot slip and the duty factor; the
torque rate comes from the traces (:mod:`cpg_actor.metrics.physical`).

The checks (CPG-RL's payload, legged_gym's pushes) run at the slow forward command on MuJoCo
(where perturbations run): a payload of :data:`PAYLOAD_SHARE` of the moving mass on the
trunk, and a push of :data:`PUSH_SPEED` m/s times the moving mass to the left and to the
right, with the robustness suite's recovery time (strides back within 10 % of the same
episode's without the push; :func:`cpg_actor.robustness.suite.recoveries`).

Ground: every row names the ground it ran on (:func:`ground_name`): the run's (flat, or the
rough ground of its ``env.terrain``), or each of the grounds asked for (:func:`terrain_level`:
every kind of tile at one difficulty level, the curriculum off).
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class GridCommand:
    """One command of the grid, held for a whole episode."""

    name: str
    vx: float  # m/s, forward
    vy: float  # m/s, to the left
    yaw: float  # rad/s, counter-clockwise

    @property
    def values(self) -> tuple[float, float, float]:
        return (self.vx, self.vy, self.yaw)

    @property
    def moves(self) -> bool:
        """Whether it asks the base to travel (a planar speed above the task's ``MOVING``):
        the cost of transport is reported for those commands alone."""
        from cpg_actor.tasks.velocity import MOVING

        return math.hypot(self.vx, self.vy) > MOVING


GRID = (
    GridCommand("forward 0.5", 0.5, 0.0, 0.0),
    GridCommand("forward 1.0", 1.0, 0.0, 0.0),
    GridCommand("backward 0.5", -0.5, 0.0, 0.0),
    GridCommand("backward 1.0", -1.0, 0.0, 0.0),
    GridCommand("left 0.3", 0.0, 0.3, 0.0),
    GridCommand("right 0.3", 0.0, -0.3, 0.0),
    GridCommand("turn left 0.5", 0.0, 0.0, 0.5),
    GridCommand("turn left 1.0", 0.0, 0.0, 1.0),
    GridCommand("turn right 0.5", 0.0, 0.0, -0.5),
    GridCommand("turn right 1.0", 0.0, 0.0, -1.0),
    GridCommand("combined", 0.5, 0.2, 0.3),
    GridCommand("standing", 0.0, 0.0, 0.0),
)
CHECK_COMMAND = GRID[0]  # the checks' command: 0.5 m/s forward
PAYLOAD_SHARE = 1.15  # x the moving mass on the trunk (CPG-RL's 115 %)
PUSH_SPEED = 1.0  # m/s given to the moving mass by a push (legged_gym's largest)
PUSH_TIME = (1.0, 2.0)  # s: the window the push comes in (the robustness suite's)

# the table's columns: (key, heading); the env's episode metrics and the physical torque rate
COLUMNS = (
    ("lin_vel_error", "lin vel err (m/s)"),
    ("lin_vel_offset", "offset (m/s)"),
    ("yaw_rate_error", "yaw err (rad/s)"),
    ("yaw_rate_offset", "offset (rad/s)"),
    ("fell", "falls"),
    ("planar_cost_of_transport", "CoT"),
    ("torque_rate", "torque rate (N m/s)"),
    ("foot_slip", "foot slip (m/s)"),
    ("duty_factor", "duty factor"),
)
COMMAND_FIELDS = ("command_range", "lateral_range", "yaw_range")


def check_grid_robot(robot_name: str, env_config: Any) -> None:
    """ValueError, one line, unless the run's env takes forward, lateral and yaw commands (a
    quadruped's velocity task)."""
    if not all(hasattr(env_config, name) for name in COMMAND_FIELDS):
        raise ValueError(f"--grid evaluates the quadrupeds' velocity task (forward, lateral and "
                         f"yaw commands); the {robot_name}'s env has none: pass a run of a "
                         f"quadruped (go1, anymal)")  # fmt: skip


def untrained_commands(env_config: Any, grid: Sequence[GridCommand] = GRID) -> list[str]:
    """The grid's commands outside the ranges the run was trained on (its env config's
    ``command_range``, ``lateral_range``, ``yaw_range``): a forward-only run has never seen a
    lateral or turning command. Standing is in every range that holds 0, or trained with a
    standing share."""
    ranges = [tuple(getattr(env_config, name)) for name in COMMAND_FIELDS]
    standing = getattr(env_config, "standing_share", 0.0) > 0
    out = []
    for command in grid:
        if standing and command.values == (0.0, 0.0, 0.0):
            continue
        if not all(low - 1e-9 <= v <= high + 1e-9
                   for v, (low, high) in zip(command.values, ranges, strict=True)):  # fmt: skip
            out.append(command.name)
    return out


def ground_name(env_config: Any) -> str:
    """The ground an env config walks on, in words: ``flat``, or its terrain's kinds (``all``
    for every one) and start level (``curriculum`` where the level moves)."""
    terrain = getattr(env_config, "terrain", None)
    if terrain is None or not terrain.active:
        return "flat"
    from cpg_actor.terrain.config import KINDS

    kinds = "all" if set(terrain.kinds) == set(KINDS) else "+".join(terrain.kinds)
    moving = ", curriculum" if terrain.curriculum else ""
    return f"{kinds} level {terrain.start_level}{moving}"


def terrain_level(env_config: Any, level: int) -> dict[str, Any]:
    """The env changes for rough ground at difficulty ``level``: the run's terrain (every
    kind where it trained on flat ground), every robot starting on that level's tiles, the
    curriculum off (legged_gym's evaluation on one level). ValueError for a level the
    terrain does not have."""
    import dataclasses

    terrain = env_config.terrain
    kinds = terrain.kinds if terrain.active else "all"
    return {"terrain": dataclasses.replace(terrain, kinds=kinds, curriculum=False,
                                           start_level=level)}  # fmt: skip


def flat_ground(env_config: Any) -> dict[str, Any]:
    """The env changes for flat ground (none where the robot has no terrain)."""
    terrain = getattr(env_config, "terrain", None)
    return {} if terrain is None else {"terrain": type(terrain)()}


# a recipe's command process switched off, so that the grid's command is held as given (the
# field's recipes zero entries, keep them by chance, draw exponential times, or turn a heading
# into the yaw rate): each field's value that does nothing, where the config has the field
HELD_COMMAND = {"command_interval": "fixed", "command_nonzero": None, "command_hold": 0.0,
                "heading_gain": 0.0, "min_command_speed": 0.0}  # fmt: skip


def command_env(env_config: Any, command: GridCommand, ground: dict | None = None, **changes):
    """``env_config`` holding ``command`` for whole episodes on ``ground`` (env changes; None:
    the config's own): point ranges, no resampling, no standing draws, no recipe's command
    process (:data:`HELD_COMMAND`)."""
    vx, vy, yaw = command.values
    held = {name: value for name, value in HELD_COMMAND.items() if hasattr(env_config, name)}
    return env_config.replace(
        command_range=(vx, vx), lateral_range=(vy, vy), yaw_range=(yaw, yaw),
        command_resample_seconds=0.0, standing_share=0.0, **held, **(ground or {}), **changes,
    )  # fmt: skip


def push_window(episode_seconds: float) -> tuple[float, float]:
    """:data:`PUSH_TIME`, moved into the first half of an episode shorter than it."""
    half = 0.5 * episode_seconds
    return (min(PUSH_TIME[0], half), min(PUSH_TIME[1], half))


def checks(moving_mass: float, episode_seconds: float) -> list[tuple[str, dict[str, Any]]]:
    """The protocol's checks: ``(name, perturbation fields)``: the payload and the pushes to the
    left and to the right, sized by the robot's ``moving_mass`` (kg)."""
    window = push_window(episode_seconds)
    push = round(PUSH_SPEED * moving_mass, 2)
    return [
        (f"payload {PAYLOAD_SHARE:.0%}", {"payload": round(PAYLOAD_SHARE * moving_mass, 2)}),
        *((f"push {side} {PUSH_SPEED:g} m/s",
           {"push": push, "push_direction": side, "push_time": window})
          for side in ("left", "right")),
    ]  # fmt: skip


def row_of(traces: dict[str, np.ndarray]) -> dict[str, float]:
    """One row of the table from an evaluation's traces: each column's mean over the episodes
    that define it (NaN where none does; ``fell``: the share of episodes that fell)."""
    from cpg_actor.metrics.physical import torque_rate
    from cpg_actor.training.evaluation import finite_mean

    row = {key: finite_mean(traces[key]) if key in traces else math.nan for key, _ in COLUMNS}
    if "joint_torque" in traces:  # each episode's rows while it ran
        dt = float(traces["control_dt"])
        rates = [torque_rate(traces["joint_torque"][: int(length), e], dt)
                 for e, length in enumerate(traces["length"])]  # fmt: skip
        row["torque_rate"] = finite_mean(rates)
    return row


def command_row(command: GridCommand, traces: dict[str, np.ndarray]) -> dict[str, float]:
    """The row of one grid command from its evaluation (:func:`row_of`), the cost of
    transport left out (NaN) for a command that asks the base to stay: no distance asked
    for, the drift's cost means nothing."""
    row = row_of(traces)
    if not command.moves:
        row["planar_cost_of_transport"] = math.nan
    return row


def grid_means(rows: Sequence[dict[str, float]]) -> dict[str, float]:
    """Each column's mean over the grid's command rows (the NaN of an undefined one skipped;
    ``fell``: the share of the episodes that fell, with as many per command)."""
    return {key: _nanmean([r[key] for r in rows]) for key, _ in COLUMNS}


def run_grid(
    policy,
    config: Any,
    robot: Any,
    episodes: int,
    seed: int,
    grounds: Sequence[dict] = ({},),
    with_checks: bool = True,
    progress: Callable[[str], None] = print,
) -> dict[str, Any]:
    """The protocol on ``policy`` (the run's, ``config`` its TrainConfig, ``robot`` its robot):
    every command of :data:`GRID` on each of ``grounds`` (env changes: ``{}`` the run's own,
    :func:`terrain_level`), then (``with_checks``) the payload
    and push checks on MuJoCo, ``episodes`` deterministic episodes each from env seed
    ``seed``. Returns ``rows`` (each with ``terrain``, ``command`` and ``check`` names and the
    :data:`COLUMNS`), ``means`` per ground (over the grid's commands), ``untrained`` (the
    commands outside the run's training ranges) and what it ran on."""
    from cpg_actor.robustness.suite import NO_GAIT, NOT_RECOVERED, recoveries
    from cpg_actor.training.evaluation import evaluate_policy

    base = config.env
    dt = float(base.control_dt)
    rows, means, kept = [], {}, {}
    for ground in grounds:
        terrain = ground_name(command_env(base, CHECK_COMMAND, ground))
        grid_rows = []
        for command in GRID:
            config.env = command_env(base, command, ground)
            traces = evaluate_policy(policy, config, episodes, seed=seed)
            row = {
                "terrain": terrain,
                "command": command.name,
                "check": "",
                "vx": command.vx,
                "vy": command.vy,
                "yaw": command.yaw,
                **command_row(command, traces),
            }
            grid_rows.append(row)
            if command == CHECK_COMMAND and robot.simulator(config.env) == "mujoco":
                kept[terrain] = traces  # the checks' nominal episodes
            progress(f"  {terrain}, {command.name}: lin vel error {row['lin_vel_error']:.3f} "
                     f"m/s, yaw-rate error {row['yaw_rate_error']:.3f} rad/s, falls "
                     f"{row['fell']:.0%}")  # fmt: skip
        rows += grid_rows
        means[terrain] = grid_means(grid_rows)
        if not with_checks:
            continue
        mujoco = command_env(base, CHECK_COMMAND, ground, **robot.simulator_config("mujoco"))
        if terrain not in kept:  # the run is on MJX: the nominal episodes again, on MuJoCo
            config.env = mujoco
            kept[terrain] = evaluate_policy(policy, config, episodes, seed=seed)
        table = robot.perturbations
        for name, fields in checks(type(base).moving_mass, base.episode_seconds):
            config.env = mujoco.replace(perturbation=type(mujoco.perturbation)(**fields))
            traces = evaluate_policy(policy, config, episodes, seed=seed)
            row = {"terrain": terrain, "command": CHECK_COMMAND.name, "check": name,
                   "vx": CHECK_COMMAND.vx, "vy": CHECK_COMMAND.vy, "yaw": CHECK_COMMAND.yaw,
                   **row_of(traces), **fields}  # fmt: skip
            if "push" in fields:
                steps = recoveries(traces, kept[terrain], table)
                done = [s for s in steps if s not in (NOT_RECOVERED, NO_GAIT)]
                gait = [s for s in steps if s != NO_GAIT]
                row["recovered"] = len(done) / len(gait) if gait else math.nan
                row["recovery_seconds"] = float(np.mean(done)) * dt if done else math.nan
                row["push_time"] = list(fields["push_time"])
            rows.append(row)
            progress(f"  {terrain}, {name}: lin vel error {row['lin_vel_error']:.3f} m/s, "
                     f"falls {row['fell']:.0%}")  # fmt: skip
    config.env = base
    return {"rows": rows, "means": means, "untrained": untrained_commands(base),
            "episodes": episodes, "env_seed": seed, "episode_seconds": base.episode_seconds,
            "simulator": robot.simulator(base)}  # fmt: skip


def _nanmean(values: Sequence[float]) -> float:
    finite = [v for v in values if math.isfinite(v)]
    return float(np.mean(finite)) if finite else math.nan


def _cell(key: str, value: Any) -> str:
    if not isinstance(value, float) or not math.isfinite(value):
        return "—" if isinstance(value, float) else str(value)
    if key in ("fell", "recovered"):
        return f"{value:.0%}"
    return f"{value:.3f}" if abs(value) < 100 else f"{value:.0f}"


def table_lines(result: dict[str, Any]) -> list[str]:
    """The protocol's result as a printed table: a line per row, the means over the grid per
    terrain, the checks with their recovery, and footnotes."""
    untrained = set(result["untrained"])
    heads = ["terrain", "command", *(head for _, head in COLUMNS), "recovered",
             "recovery (s)"]  # fmt: skip
    body = []
    for row in result["rows"]:
        name = row["check"] or row["command"]
        if not row["check"] and row["command"] in untrained:
            name += " *"
        body.append([row["terrain"], name, *(_cell(k, row[k]) for k, _ in COLUMNS),
                     _cell("recovered", row.get("recovered", "")),
                     _cell("", row.get("recovery_seconds", ""))])  # fmt: skip
    for terrain, mean in result["means"].items():
        body.append([terrain, "mean over the grid", *(_cell(k, mean[k]) for k, _ in COLUMNS),
                     "", ""])  # fmt: skip
    widths = [max(len(r[i]) for r in [heads, *body]) for i in range(len(heads))]

    def line(cells: list[str]) -> str:
        return "  ".join(c.ljust(w) if i < 2 else c.rjust(w)
                         for i, (c, w) in enumerate(zip(cells, widths, strict=True)))  # fmt: skip

    lines = [line(heads), line(["-" * w for w in widths]), *(line(r) for r in body)]
    lines.append(
        f"{result['episodes']} episode(s) of {result['episode_seconds']:g} s per row "
        f"from env seed {result['env_seed']}, on {result['simulator']} (checks on "
        f"mujoco, at {CHECK_COMMAND.vx:g} m/s forward); errors: means over the episode of "
        f"the per-step errors, start-up included; offsets: the errors of the episode's mean "
        f"velocity; —: undefined (CoT: for the commands that travel, a path of 0.1 m or more)"
    )
    if untrained:
        lines.append("*: outside the ranges the run was trained on (its env's command_range, "
                     "lateral_range, yaw_range)")  # fmt: skip
    return lines


def csv_text(result: dict[str, Any]) -> str:
    """The rows and the means as CSV: one line per row, the means with command ``mean``."""
    keys = ["terrain", "command", "check", "vx", "vy", "yaw", *(k for k, _ in COLUMNS),
            "payload", "push", "push_direction", "recovered", "recovery_seconds"]  # fmt: skip
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=keys, extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    for row in result["rows"]:
        writer.writerow(row)
    for terrain, mean in result["means"].items():
        writer.writerow({"terrain": terrain, "command": "mean", **mean})
    return out.getvalue()


def json_text(result: dict[str, Any]) -> str:
    """The result as JSON, NaN written as null."""

    def clean(value):
        if isinstance(value, float) and not math.isfinite(value):
            return None
        if isinstance(value, dict):
            return {k: clean(v) for k, v in value.items()}
        if isinstance(value, list | tuple):
            return [clean(v) for v in value]
        return value

    return json.dumps(clean(result), indent=2) + "\n"


def read_json(text: str) -> dict[str, Any]:
    """A result :func:`json_text` wrote, each null (an undefined number) read back as NaN."""

    def nan_for_null(mapping: dict[str, Any]) -> dict[str, Any]:
        return {k: math.nan if v is None else v for k, v in mapping.items()}

    return json.loads(text, object_hook=nan_for_null)
