"""Time to quality on the hopper, fairly: wall time and env steps until a deterministic
evaluation reaches one target, the same for every method (a return AND a hop apex), each
warm-started method charged for its start, with best-so-far curves against wall time and
against env steps. The full measurement (about 1-2 hours on 2 cores; SB3's single env is the
longest):

    python benchmarks/time_to_quality.py --seeds 3 \\
        --agents cpg-actor,mlp,mlp-warm,cho2019-warm,open-loop-es --preset paper \\
        --budget 500000 --target-return 850 --target-apex 0.50 \\
        --output benchmarks/results/time_to_quality.md

and the search-budget sweep of the agents that start from the searched gait (issue 53,
item 4), add ``--search-budgets 50000,150000,496000``.

The target. One evaluation (:class:`cpg_actor.training.evaluation.TrainingEvaluation`, the
trainer's own: the mean action, ``EVAL_EPISODES`` episodes on envs of their own, the run's
evaluation seed) meets it when its mean return is >= ``--target-return`` and its mean hop apex
is >= ``--target-apex``. The hop apex is :func:`cpg_actor.metrics.physical.hop_apex` (the
median over an episode's flights, after the start-up, of the highest hip height above
standing), not the episode's highest hip height: the training-time evaluation gives it when
asked (``TrainingEvaluation.traced_metrics``: the episodes are traced, which costs each evaluation
about nothing next to the physics, and evaluations are not timed). The defaults (850, 0.50 m)
lie above the searched start gait's evaluation (return about 690, apex 0.49 m: a method that
starts there does not meet it before learning) and below what the tuned warm-started agents
reach in 500k steps on tuning seeds (returns 930-1050, hop heights 0.56-0.58 m;
``docs/results/tuning``). ``mlp`` (no warm start) hops about 0.29 m there: it may never meet it.

The start is charged. Every method is evaluated before its first update and every
``EVAL_EVERY`` env steps. A method that starts from the searched gait
(``agent_config.start_gait: search``: ``cpg-actor``, ``mlp-warm``, ``cho2019-warm``) is
charged that gait's search: the open-loop search (``open-loop-es``, CMA-ES) is rerun here as
the packaged gait file records it (its seed and ``steps_searched``, or each of
``--search-budgets``), in a fresh process, and its env steps and wall time (generations,
evaluations excluded) are added to the method's; those methods start from the gait this rerun
found (``--start packaged``: from the file's gait, still charged the rerun's cost; the search
does not find the file's gait again with today's package, see the report). ``mlp-warm`` and
``cho2019-warm`` are also charged their supervised warm start (``warm_start.rollout_steps``
control steps on each of the ``num_envs`` envs, and the fit's wall time). ``open-loop-es`` is
the search itself, one per seed, with the methods' budget: nothing to add. Curves and times are
"start + own": a charged method's curve begins where its start ends.

SB3 (``pip install stable-baselines3``, an optional dependency; skipped with a line when it is
not installed) runs PPO ``MlpPolicy`` with its defaults on the registered env
``cpg_actor/AnymalHopper-v0`` (actions rescaled to [-1, 1], no VecNormalize): once with its
default single env, once with ``make_vec_env`` and the project run's ``num_envs`` (its
defaults otherwise: ``n_steps`` 2,048 per env), with the same budget, target and evaluation.
The physics ceiling (``mujoco.rollout``, :func:`time_to_target.hopper_ceiling`) is measured in
the same run at each env count used. Runs go one at a time, each project run and search in a
fresh process; time is training wall time (collection and update, compilation included,
evaluations excluded). ``--resume`` goes on from a run cut off part way (its searches and
finished (method, seed) runs are saved after each, in ``OUTPUT`` with ``.partial.json``); the
report names the machines when a resumed run moved. Beside the report go its figure and every
run's curve as JSON (the same name, ``.png`` and ``.json``); beside a report named by
``--output``, an existing file of those names is refused unless ``--overwrite``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import sys
import tempfile
from pathlib import Path
from typing import NamedTuple

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import time_to_target as shared  # noqa: E402 (benchmarks/ on the path first)
from time_to_target import (  # noqa: E402
    RunSpec,
    charged,
    evaluation_recorder,
    gait_difference,
    median_or_none,
    over_seeds,
    recorded_search,
    sb3_history,
    search_result,
)

OUTPUT = "benchmarks/results/time_to_quality.md"

AGENTS = ("cpg-actor", "mlp", "mlp-warm", "cho2019-warm", "open-loop-es")
BUDGET = 500_000  # env steps of each method's own training (after its start)
TARGET_RETURN = 850.0
TARGET_APEX = 0.50  # m
EVAL_EVERY = 10_240  # env steps between evaluations
EVAL_EPISODES = 5
SB3_LABEL = "SB3 PPO (MLP, defaults), {} env{}"


# -- the target logic (pure; tested) ---------------------------------------------------------
class Target(NamedTuple):
    """One target for every method: a mean return AND a mean hop apex (m), in one evaluation."""

    ret: float
    apex: float

    def met(self, point: dict) -> bool:
        return point["return"] >= self.ret and point["apex"] >= self.apex

    def describe(self) -> str:
        return f"return >= {self.ret:g} and hop apex >= {self.apex:g} m"


def best_so_far(history: list[dict]) -> list[dict]:
    """At each evaluation, the best return and the best hop apex of the evaluations up to it
    (each its own maximum; NaN values skipped), with its ``steps`` and ``wall``."""
    best_return, best_apex = -math.inf, -math.inf
    curve = []
    for h in history:
        if math.isfinite(h["return"]):
            best_return = max(best_return, h["return"])
        if math.isfinite(h["apex"]):
            best_apex = max(best_apex, h["apex"])
        curve.append({"steps": h["steps"], "wall": h["wall"],
                      "return": best_return if math.isfinite(best_return) else math.nan,
                      "apex": best_apex if math.isfinite(best_apex) else math.nan})  # fmt: skip
    return curve


def first_at_target(history: list[dict], target: Target) -> dict | None:
    """The first evaluation that met ``target`` (both thresholds in the same evaluation; a
    best return in one and a best apex in another do not count), or None."""
    return shared.first_at_target(history, target.met)


# -- one project run, one search (fresh processes) ---------------------------------------------
def run_config(agent: str, preset: str, seed: int, values: list[dict], budget: int):
    """The run's config as ``cpg-actor train`` composes it, with the benchmark's evaluation."""
    return shared.run_config(agent, preset, seed, values, budget, EVAL_EVERY, EVAL_EPISODES)


def point(steps: int, wall: float, evaluation: dict[str, float]) -> dict:
    """An evaluation as a curve's point."""
    return {"steps": int(steps), "wall": float(wall),
            "return": float(evaluation["eval/return"]),
            "apex": float(evaluation.get("eval/hop_apex", math.nan)),
            "hop": float(evaluation.get("eval/hop_height", math.nan))}  # fmt: skip


def train(config, stop) -> tuple[list[dict], dict, object]:
    """Train ``config`` in this process with every evaluation recorded (hop apex included)
    and its warm start timed; ``(history, warm start's {"steps", "wall"}, runner)`` (the
    runner closed)."""
    from cpg_actor.metrics.physical import episode_metrics

    def traced(runner) -> None:  # eval/hop_apex from the evaluations' traces
        runner.evaluation.traced_metrics = episode_metrics

    recorder = evaluation_recorder(stop)
    warm, runner = shared.train(config, recorder, setup=traced)
    return [point(s, w, e) for s, w, e in recorder.history], warm, runner


def project_run(spec: RunSpec) -> dict:
    """One run (its ``target``: a :class:`Target`'s values): ``history`` (every evaluation),
    its warm start (``warm_steps``, ``warm_wall``) and ``num_envs``."""
    config = run_config(spec.agent, spec.preset, spec.seed, spec.values, spec.budget)
    target = Target(*spec.target)
    history, warm, _ = train(
        config, (lambda e: target.met(point(0, 0.0, e))) if spec.stop else None
    )
    return {"history": history, "warm_steps": warm["steps"], "warm_wall": warm["wall"],
            "num_envs": config.num_envs}  # fmt: skip


class SearchSpec(NamedTuple):
    """The open-loop search behind the packaged start gait of ``agent`` (with ``preset`` and
    the env values of ``values``), with ``budget`` env steps (None: the file's
    ``steps_searched``), its gait written to ``path``. JSON-able."""

    agent: str
    preset: str
    values: list[dict]
    budget: int | None
    path: str


def search_run(spec: SearchSpec) -> dict:
    """The search rerun as the gait file records it: its env steps and wall time, its
    evaluations, the gait it found (written to ``spec.path``) and how far that is from the
    file's (0.0: the same gait)."""
    from cpg_actor.agents.gait_file import write_gait

    source = shared.start_gait_file(spec.agent, spec.preset, spec.values)
    gait, search = recorded_search(source, spec.budget, spec.values)  # on the runs' physics
    values = [{key: search[key] for key in ("robot", "es", "env") if key in search}]
    config = run_config(search["agent"], spec.preset, search["seed"], values,
                        search["total_steps"])  # fmt: skip
    history, _, runner = train(config, None)
    found = runner.gait()
    write_gait(spec.path, found)
    difference = gait_difference(found["cpg_initial"], gait["cpg_initial"])
    return {**search_result(source, config, runner, spec.path, difference), "history": history}


def in_fresh_process(flag: str, spec: NamedTuple) -> dict:
    return shared.in_fresh_process(__file__, flag, spec, show_stderr=True)


# -- SB3 ----------------------------------------------------------------------------------------
def sb3_run(seed: int, num_envs: int, values: list[dict], budget: int, target: Target,
            stop: bool) -> dict:  # fmt: skip
    """SB3's PPO with its defaults on ``num_envs`` envs (``make_vec_env``), evaluated as the
    project's runs (the same evaluation, hop apex from its traces)."""
    import gymnasium as gym
    from stable_baselines3.common.env_util import make_vec_env

    from cpg_actor.metrics.physical import episode_metrics
    from cpg_actor.robots.hopper.plugin import ENV_ID
    from cpg_actor.training.evaluation import finite_mean

    physics = shared.env_values(values)  # --set env.KEY=VALUE reaches SB3's env too
    env = make_vec_env(ENV_ID, n_envs=num_envs, seed=seed, env_kwargs=physics,
                       wrapper_class=gym.wrappers.RescaleAction,
                       wrapper_kwargs={"min_action": -1.0, "max_action": 1.0})  # fmt: skip

    def numbers(result: dict) -> dict:
        apex = episode_metrics(result).get("hop_apex", np.array([math.nan]))
        return {"return": float(result["episode_return"].mean()), "apex": finite_mean(apex),
                "hop": finite_mean(result["hop_height"])}  # fmt: skip

    history = sb3_history(env, seed, budget, physics, EVAL_EVERY, EVAL_EPISODES, numbers,
                          target.met, stop, traces=True)  # fmt: skip
    return {"history": history, "warm_steps": 0, "warm_wall": 0.0, "num_envs": num_envs}


# -- the report ---------------------------------------------------------------------------------
class Method(NamedTuple):
    """A row of the report: ``kind`` "project" (``agent``, from the search of
    ``search_budget`` if it starts from the searched gait) or "sb3" (on ``num_envs``)."""

    label: str
    kind: str
    agent: str
    num_envs: int
    search_budget: int | None


def summarize(run: dict, search: dict | None, target: Target) -> dict:
    """A run with its start charged: ``start_steps``/``start_wall`` (the search's and the
    warm start's), ``curve`` (its evaluations, charged), ``hit`` (the first at the target,
    charged, or None), its best return and apex."""
    start_steps = run["warm_steps"] + (search["steps"] if search else 0)
    start_wall = run["warm_wall"] + (search["wall"] if search else 0.0)
    curve = charged(run["history"], start_steps, start_wall)
    best = best_so_far(curve)
    return {**run, **shared.to_target(run["history"], target.met), "start_steps": start_steps,
            "start_wall": start_wall, "curve": curve, "hit": first_at_target(curve, target),
            "best_return": best[-1]["return"] if best else math.nan,
            "best_apex": best[-1]["apex"] if best else math.nan}  # fmt: skip


class State:
    """A cut-off run's progress, to go on from with ``--resume``: the command's arguments, each
    search (its gait file's text with it) and each finished (method, seed) result, in
    ``path``, rewritten after each (atomically)."""

    def __init__(self, path: Path, arguments: list[str]) -> None:
        self.path = path
        self.data: dict = {"arguments": arguments, "searches": {}, "results": {}}

    def load(self) -> None:
        """ValueError, one line, where there is nothing to go on from or another command
        made it."""
        if not self.path.is_file():
            raise ValueError(f"--resume: no {self.path} to go on from (a run of this command "
                             "writes it after each run)")  # fmt: skip
        saved = json.loads(self.path.read_text())
        if saved.get("arguments") != self.data["arguments"]:
            raise ValueError(f"--resume: {self.path} was made by another command "
                             f"({' '.join(saved.get('arguments', []))}); give the same "
                             "arguments")  # fmt: skip
        self.data = saved

    def _save(self) -> None:
        from cpg_actor.files import atomic_write_text

        atomic_write_text(json.dumps(self.data) + "\n", self.path)

    def search(self, budget: int | None, path: str) -> dict | None:
        """The saved search of ``budget``, its gait written to ``path``; None if not saved."""
        saved = self.data["searches"].get(str(budget))
        if saved is None:
            return None
        Path(path).write_text(saved["gait_text"])
        return {**{k: v for k, v in saved.items() if k != "gait_text"}, "gait": path}

    def add_search(self, budget: int | None, search: dict) -> None:
        self.data["searches"][str(budget)] = {
            **search,
            "gait_text": Path(search["gait"]).read_text(),
        }
        self._save()

    def result(self, label: str, seed: int) -> dict | None:
        return next((r for r in self.data["results"].get(label, []) if r["seed"] == seed), None)

    def add_result(self, label: str, result: dict) -> None:
        self.data["results"].setdefault(label, []).append(result)
        self._save()


def kilo(steps: float) -> str:
    return f"{steps / 1000:,.0f}k"


def method_row(method: Method, runs: list[dict]) -> str:
    hits, steps, wall = over_seeds(runs)  # the start charged
    start_steps = median_or_none([r["start_steps"] for r in runs]) or 0
    start_wall = median_or_none([r["start_wall"] for r in runs]) or 0.0
    start = f"{kilo(start_steps)}, {start_wall:.0f} s" if start_steps else "none"
    per_seed = "; ".join(
        f"{kilo(r['hit']['steps'])}, {r['hit']['wall']:.0f} s" if r["hit"] is not None
        else f"not in {kilo(r['curve'][-1]['steps'] if r['curve'] else 0)}"
        for r in runs
    )  # fmt: skip
    cells = [
        method.label, str(method.num_envs), start, f"{hits}/{len(runs)}",
        "-" if steps is None else f"**{kilo(steps)}**",
        "-" if wall is None else f"**{wall:.0f} s**",
        f"{np.nanmedian([r['best_return'] for r in runs]):.0f}",
        f"{np.nanmedian([r['best_apex'] for r in runs]):.3f} m",
        per_seed,
    ]  # fmt: skip
    return "| " + " | ".join(cells) + " |"


def figure(path: Path, methods: list[Method], results: dict[str, list[dict]],
           target: Target) -> None:  # fmt: skip
    """Best-so-far return and hop apex against env steps and wall time (the start charged:
    a charged curve begins where its start ends, marked with a dot), a line per seed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from cpg_actor.plots import save_figure

    fig, axes = plt.subplots(2, 2, figsize=(10, 6.5), sharey="row")
    palette = plt.get_cmap("tab10" if len(methods) <= 10 else "tab20")
    colours = [palette(i % palette.N) for i in range(len(methods))]  # the sweep has more
    for i, method in enumerate(methods):
        for j, run in enumerate(results[method.label]):
            curve = best_so_far(run["curve"])
            if not curve:
                continue
            for row, key in enumerate(("return", "apex")):
                for col, x in enumerate(("steps", "wall")):
                    xs = [c[x] / (1e3 if x == "steps" else 1.0) for c in curve]
                    ax = axes[row, col]
                    ax.step(
                        xs,
                        [c[key] for c in curve],
                        where="post",
                        color=colours[i],
                        lw=1.2,
                        alpha=0.8,
                        label=method.label.replace("`", "") if j == 0 else None,
                    )
                    if run["start_steps"]:
                        ax.plot(xs[0], curve[0][key], "o", ms=3, color=colours[i])
    for col, x in enumerate(("env steps (thousands, start included)",
                             "wall time (s, start included)")):  # fmt: skip
        axes[1, col].set_xlabel(x)
        axes[0, col].axhline(target.ret, ls="--", color="grey", lw=0.8)
        axes[1, col].axhline(target.apex, ls="--", color="grey", lw=0.8)
    axes[0, 0].set_ylabel("best return so far")
    axes[1, 0].set_ylabel("best hop apex so far (m)")
    axes[0, 0].legend(fontsize=7, loc="lower right")
    fig.suptitle(f"Time to quality (target: {target.describe()}, dashed)", fontsize=10)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def report(methods: list[Method], results: dict[str, list[dict]], searches: dict,
           target: Target, args, sb3_note: str, start_note: str, ceilings: dict[int, float],
           provenance: str, figure_name: str) -> list[str]:  # fmt: skip
    lines = [
        "# Time to quality: the same target for every method, every start charged",
        "",
        provenance,
        "",
        f"Target: one evaluation with mean **{target.describe()}** (the mean over "
        f"{EVAL_EPISODES} deterministic episodes of the trainer's own evaluation; the hop apex "
        "is `cpg_actor/metrics/physical.py`'s `hop_apex` from the evaluation's traces, not the "
        "episode's highest hip height). Evaluated before the first update and every "
        f"{EVAL_EVERY:,} env steps; each method trains {args.budget:,} env steps of its own"
        + (" or stops at the target" if args.stop_at_target else "")
        + ". Env steps and wall time are the start's plus the method's own (training wall "
        "time, evaluations excluded): medians over the seeds that reached the target. "
        + start_note,
    ]
    if sb3_note:
        lines += ["", sb3_note]
    if any(m.kind == "sb3" for m in methods):
        lines += [
            "",
            "SB3: PPO `MlpPolicy` with its defaults on `cpg_actor/AnymalHopper-v0` (actions "
            "rescaled to [-1, 1], no VecNormalize), in this process with 1 torch thread (as "
            "the project's runs), with 1 env and with `make_vec_env` and the project run's "
            "envs; with N envs it collects 2,048 x N env steps per update, so its budget "
            "rounds up to whole rollouts.",
        ]
    if searches:
        lines += [
            "",
            "## The start gait's searches (charged)",
            "",
            "| search | env steps | wall time | its last evaluation: return, apex | the "
            "gait found against the file's |",
            "| --- | ---: | ---: | ---: | --- |",
        ]
        for search in searches.values():
            last = search["history"][-1] if search["history"] else None
            shown = "-" if last is None else f"{last['return']:.0f}, {last['apex']:.3f} m"
            same = (
                "**the same gait**"
                if search["difference"] == 0
                else f"differs (largest relative difference {search['difference']:.2g})"
            )
            lines.append(f"| `{search['agent']}`, seed {search['seed']}, budget "
                         f"{search['budget']:,} | {search['steps']:,} | {search['wall']:.0f} s "
                         f"| {shown} | {same} |")  # fmt: skip
    lines += [
        "", "## Time to the target", "",
        "| method | envs | start charged (env steps, wall) | seeds at target | env steps to "
        "it | wall time to it | best return | best apex | per seed (steps, wall to it) |",
        "| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | --- |",
    ]  # fmt: skip
    lines += [method_row(m, results[m.label]) for m in methods if results[m.label]]
    lines += [
        "", f"![best-so-far curves]({figure_name})", "",
        "Best return and best apex: the medians over seeds of each seed's best evaluation "
        "(each its own maximum, possibly in different evaluations).", "",
        "Physics ceiling in the same run (`mujoco.rollout`, constant torques): "
        + ", ".join(f"{v:,.0f} control steps/s at N={n}" for n, v in ceilings.items()) + ".",
    ]  # fmt: skip
    return lines


# -- main ---------------------------------------------------------------------------------------
def positive_int(text: str) -> int:
    if not text.isdigit() or int(text) <= 0:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a positive integer")
    return int(text)


def budgets_list(text: str) -> list[int]:
    return [positive_int(t) for t in text.split(",")]


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if shared.answer(argv, {"--one-run": (RunSpec, project_run),
                            "--one-search": (SearchSpec, search_run)}):  # fmt: skip
        return 0
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=positive_int, default=3)
    parser.add_argument(
        "--first-seed",
        type=int,
        default=0,
        help="seeds FIRST..FIRST+N-1 (default 0; fresh report seeds need a protocol first: "
        "docs/results/SEEDS.md)",
    )
    parser.add_argument("--agents", default=",".join(AGENTS))
    parser.add_argument("--preset", default="paper")
    parser.add_argument(
        "--budget",
        type=positive_int,
        default=BUDGET,
        help="env steps of each method's own training (default 500000)",
    )
    parser.add_argument("--target-return", type=float, default=TARGET_RETURN)
    parser.add_argument("--target-apex", type=float, default=TARGET_APEX, help="m")
    parser.add_argument(
        "--stop-at-target",
        action="store_true",
        help="stop a run at the target (its curve then ends there)",
    )
    parser.add_argument(
        "--search-budgets",
        type=budgets_list,
        default=None,
        metavar="STEPS[,STEPS...]",
        help="the start gait's search with each budget (the methods that "
        "start from it once per budget); default: the gait file's",
    )
    parser.add_argument(
        "--start",
        choices=("found", "packaged"),
        default="found",
        help="start from the gait the rerun search found (default) or from "
        "the packaged file's, charged the rerun's cost either way",
    )
    parser.add_argument("--no-sb3", action="store_true", help="skip Stable-Baselines3")
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a config value for every run (env.* reach the searches and SB3's env too)",
    )
    parser.add_argument("--ceiling-steps", type=positive_int, default=50_000)
    parser.add_argument(
        "--output",
        default=OUTPUT,
        help=f"the report (default {OUTPUT}); its figure and JSON go beside it "
        "(the same name, .png and .json)",
    )
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="replace an existing figure or JSON beside a named --output",
    )
    parser.add_argument(
        "--resume",
        action="store_true",
        help="go on from the runs and searches an earlier, cut-off run of the same command "
        "saved (OUTPUT with .partial.json; written after each run, removed at the end)",
    )
    args = parser.parse_args(argv)  # fmt: skip
    if not (math.isfinite(args.target_return) and math.isfinite(args.target_apex)):
        parser.error("--target-return and --target-apex must be finite numbers")

    from bench_report import companions, measured, write
    from cpg_actor.agents import get_agent_spec
    from cpg_actor.config import parse_override
    from cpg_actor.machine import cpu_model, load_average, usable_cores
    from time_to_target import hopper_ceiling, start_gait_file

    agents = args.agents.split(",")
    for agent in agents:
        try:
            get_agent_spec(agent)
        except (KeyError, ValueError):
            parser.error(f"--agents: unknown agent {agent!r} (e.g. {', '.join(AGENTS)})")
    try:  # --set read and checked as `cpg-actor train --set`, before anything runs
        values = [parse_override(text) for text in args.overrides]
        for agent in agents:
            run_config(agent, args.preset, 0, values, args.budget)
    except (ValueError, FileNotFoundError) as error:
        parser.error(f"the runs' config (with --set): {error}")
    target = Target(args.target_return, args.target_apex)
    output = Path(args.output)
    sb3 = not args.no_sb3 and importlib.util.find_spec("stable_baselines3") is not None
    sb3_note = "" if sb3 or args.no_sb3 else (
        "Stable-Baselines3 is not installed here (`pip install stable-baselines3`), so its "
        "PPO was not run.")  # fmt: skip
    if sb3_note:
        print(sb3_note, flush=True)
    import torch

    torch.set_num_threads(1)  # SB3 here; each project run sets its own threads
    num_envs = run_config("mlp", args.preset, 0, values, args.budget).num_envs
    methods: list[Method] = []
    searched = [a for a in agents if start_gait_file(a, args.preset, values) is not None]
    gait_files = {start_gait_file(a, args.preset, values) for a in searched}
    if len(gait_files) > 1:  # one search is rerun and charged to them all
        parser.error(
            f"{', '.join(searched)} start from different gait files "
            f"({', '.join(sorted(map(str, gait_files)))}); this benchmark reruns one search: "
            "give agents that start from the same gait"
        )
    for agent in agents:
        per_budget = args.search_budgets if agent in searched and args.search_budgets else [None]
        for budget in per_budget:
            suffix = f" (search {kilo(budget)})" if budget else ""
            config = run_config(agent, args.preset, 0, values, args.budget)
            envs = config.num_envs  # the search steps its population's envs
            if get_agent_spec(agent).trainer == "es":
                envs = config.es.popsize * config.es.episodes
            methods.append(Method(f"`{agent}`{suffix}", "project", agent, envs, budget))
    if sb3:
        for n in sorted({1, num_envs}):
            methods.append(Method(SB3_LABEL.format(n, "" if n == 1 else "s"), "sb3", "", n, None))
    results: dict[str, list[dict]] = {m.label: [] for m in methods}
    searches: dict[int | None, dict] = {}
    state = State(output.with_suffix(".partial.json"), [a for a in argv if a != "--resume"])
    if args.resume:
        try:
            state.load()
        except ValueError as error:
            parser.error(str(error))
    elif state.path.exists():
        parser.error(f"{state.path} holds an earlier run's progress: add --resume to go on "
                     "from it, or delete it to start over")  # fmt: skip
    # after the progress's checks (a --resume with nothing to go on from says that first),
    # before any run
    figure_path, json_path = companions(parser, output, (".png", ".json"),
                                        args.output != OUTPUT, args.overwrite)  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="time_to_quality_") as directory:
        for budget in sorted({m.search_budget for m in methods if m.agent in searched},
                             key=lambda b: b or 0):  # fmt: skip
            path = str(Path(directory) / f"gait_{budget or 'file'}.yaml")
            searches[budget] = state.search(budget, path)
            if searches[budget] is None:
                spec = SearchSpec(searched[0], args.preset, values, budget, path)
                searches[budget] = in_fresh_process("--one-search", spec)
                state.add_search(budget, searches[budget])
            print(f"search {budget or 'file'}: {searches[budget]['steps']:,} steps, "
                  f"{searches[budget]['wall']:.0f} s", flush=True)  # fmt: skip
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            for method in methods:
                done = state.result(method.label, seed)
                if done is not None:
                    results[method.label].append(done)
                    continue
                search = searches.get(method.search_budget) if method.agent in searched else None
                if method.kind == "sb3":
                    run = sb3_run(seed, method.num_envs, values, args.budget, target,
                                  args.stop_at_target)  # fmt: skip
                else:
                    run_values = list(values)
                    if search is not None and args.start == "found":  # the gait it found
                        run_values.append({"agent_config": {"start_gait": search["gait"]}})
                    spec = RunSpec(method.agent, args.preset, seed, run_values, args.budget,
                                   list(target), args.stop_at_target)  # fmt: skip
                    run = in_fresh_process("--one-run", spec)
                results[method.label].append({**summarize(run, search, target), "seed": seed,
                                              "machine": cpu_model()})  # fmt: skip
                state.add_result(method.label, results[method.label][-1])
                hit = results[method.label][-1]["hit"]
                print(
                    f"seed {seed} {method.label}: "
                    f"{'at target ' + str(hit) if hit else 'target not reached'}",
                    flush=True,
                )
    sizes = sorted({m.num_envs for m in methods})
    ceilings = {n: hopper_ceiling(n, args.ceiling_steps) for n in sizes}
    if args.start == "found":
        start_note = (
            "The methods that start from the searched gait start from the gait the "
            "search rerun here found."
        )
    else:
        start_note = (
            "The methods that start from the searched gait start from the packaged "
            "gait file's, charged the cost of its search rerun here."
        )
    command = "python benchmarks/time_to_quality.py " + " ".join(argv)
    provenance = (f"{measured(command)} on {cpu_model()}, {usable_cores()} usable cores "
                  f"(load {load_average()} at the end), torch {torch.__version__}; each "
                  "project run and search in a fresh process, one at a time.")  # fmt: skip
    machines: dict[str, set[int]] = {}
    for runs in results.values():
        for run in runs:
            machines.setdefault(run.get("machine", "not recorded"), set()).add(run["seed"])
    if len(machines) > 1:  # resumed on another machine: its times are not the same clock's
        provenance += " Resumed across machines: " + "; ".join(
            f"seeds {', '.join(map(str, sorted(seeds)))} on {name}"
            for name, seeds in machines.items()) + "."  # fmt: skip
    lines = report(methods, results, {b: s for b, s in searches.items()}, target, args,
                   sb3_note, start_note, ceilings, provenance, figure_path.name)  # fmt: skip
    figure_path.parent.mkdir(parents=True, exist_ok=True)
    figure(figure_path, methods, results, target)
    write(output, lines)
    from cpg_actor.files import atomic_write_text

    # per method and seed: the charged curve, its start and the first evaluation at the target
    keys = (
        "seed",
        "machine",
        "curve",
        "start_steps",
        "start_wall",
        "hit",
        "best_return",
        "best_apex",
    )
    atomic_write_text(json.dumps({m.label: [{k: r.get(k) for k in keys} for r in results[m.label]]
                                  for m in methods}), json_path)  # fmt: skip
    state.path.unlink(missing_ok=True)  # this benchmark's own progress file, now in the JSON
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONHASHSEED", "0")
    raise SystemExit(main())
