"""Wall-clock time and env steps to a deterministic hop height, per agent and preset: the
CPG-Actor's time to 0.45 m, its start gait's search included, next to the MLP's time to its own
best hop height and Stable-Baselines3's PPO (defaults), measured in the same run.

    python benchmarks/time_to_hop.py [--seeds 3] [--output benchmarks/results/time_to_hop.md]

What a user waits for is a good policy, not steps per second. Every method is evaluated the
same way (:func:`cpg_actor.training.evaluation.evaluate`: the mean action, 5 episodes on envs
of their own, the same reset seed) before its first update and every ``EVAL_EVERY`` env steps.
The targets are those of the issue "The CPG-Actor at its best": ``cpg-actor`` reaches its
threshold when one evaluation has a mean hop height >= 0.45 m (any return) and stops there,
within 500k PPO steps; ``mlp`` (and SB3) have no threshold: they train to their budget (500k
steps) and are measured to their own best hop height (the first evaluation at it, and at 95 %
of it), and to when they first met the other agents' thresholds. Time is training wall time,
evaluations excluded. Runs go one at a time (no two measurements share the CPU).

The search is charged. The default ``cpg-actor`` starts from a packaged gait
(``agent_config.start_gait: search``, ``robots/ROBOT/start_gait.yaml``) that the open-loop search
(``open-loop-es``, CMA-ES) found; the honest time to the threshold includes finding it. So,
before the seeds, the search behind each agent's start gait is rerun as its gait file records
it (``cpg-actor train --agent open-loop-es --seed SEED --total-steps STEPS``: the file's seed
and ``steps_searched``, which :func:`cpg_actor.agents.start_gait.search_steps` charges too),
once per distinct gait (every seed of every preset starting from it shares it), in a fresh
process; the report says whether it found the file's gait again. Each run of such an agent
starts from the gait found in this run, and the search's env steps and wall time (its
generations, evaluations excluded) are added to each seed's: reported as search + PPO =
total. ``--search-budget STEPS`` searches with another budget (a quick check; the gait is
then another one), ``--no-search`` charges nothing and starts from the file's gait.

SB3 (``pip install stable-baselines3``; skipped with a note when it is not installed) runs
stock: PPO ``MlpPolicy`` with its defaults (Baselines' ppo2 numbers) on the registered env
``cpg_actor/AnymalHopper-v0`` with actions rescaled to [-1, 1] and no VecNormalize, with
``mlp``'s budget and threshold. The physics ceiling (``mujoco.rollout`` on the project's MJCF,
the same N envs) is measured in the same run (``benchmarks/env_throughput.py``).

Each of the project's runs and searches is a fresh process (this script with ``--one-run`` or
``--one-search``) with ``PYTHONPATH`` set to a tree's ``src``. ``--reference-src REF/src``
also runs every agent and preset with the package of another tree (e.g. the commit before a
redesign), taking turns with this tree's runs, so the two are measured on the same machine in
the same run (its start gaits searched with its own package); ``--set`` applies to this tree's
runs, its searches' env and SB3's env, ``--reference-set`` to the reference's (a reference
older than a config key needs none: ``env.actuator_law=coast`` here is the only law before 26
Nov 2026). The ratio of the two trees' median wall times (agents with a threshold) counts a
seed that missed the threshold as later than its whole budget, so that median is a lower bound
(">="); ``--budget AGENT=STEPS`` gives an agent another budget (PPO steps; the threshold
stays); ``--threshold AGENT=RETURN,HOP`` another threshold (``AGENT=HOP`` or
``AGENT=none,HOP``: the hop height alone; ``AGENT=best``: none, to its best hop height); an
agent the issue set no budget for (``cpg-actor-open-loop``, the Cho et al. agents) needs
``--budget``, and is measured to its best hop height unless it has a threshold. Each run also
records the share of the machine's CPU time its hypervisor took meanwhile
(:func:`cpg_actor.machine.cpu_times`).
"""

from __future__ import annotations

import argparse
import datetime
import importlib.util
import json
import math
import os
import sys
import tempfile
from pathlib import Path
from typing import NamedTuple

import numpy as np

from time_to_target import (
    RunSpec,
    answer,
    censored_median_wall,
    compose,  # noqa: F401 (the tests read this benchmark's runs' config here)
    evaluation_recorder,
    first_at_target,
    from_tree,
    gait_difference,
    hopper_ceiling,
    in_fresh_process,
    over_seeds,
    recorded_search,
    run_config,
    sb3_history,
    search_result,
    split,
    start_gait_file,
    to_target,
    train,
)

# The project's imports are in the functions: a run with --one-run imports the package of the
# tree its PYTHONPATH names, which may be older than this script.
HERE = Path(__file__).resolve().parent
OUTPUT = "benchmarks/results/time_to_hop.md"

EVAL_EVERY = 10_240  # env steps between evaluations (5 iterations of 2,048 steps)
EVAL_EPISODES = 5
# The targets of the issue "The CPG-Actor at its best": cpg-actor's time to a deterministic hop
# height of 0.45 m, whatever its return (None: no return condition), next to mlp's time to its
# own best hop height. An agent with a step budget and no threshold trains to its budget and
# is measured to its best hop height.
THRESHOLDS: dict[str, tuple[float | None, float] | None] = {"cpg-actor": (None, 0.45)}
BUDGETS = {"mlp": 500_000, "cpg-actor": 500_000}
NEAR_BEST = 0.95  # "near its best": the first evaluation at this share of the best hop height


def point(steps: int, wall: float, evaluation: dict[str, float]) -> dict:
    """An evaluation at ``steps`` env steps and ``wall`` s of training: its mean return and
    hop height."""
    return {"steps": steps, "wall": wall, "return": evaluation["eval/return"],
            "hop": evaluation["eval/hop_height"]}  # fmt: skip


def reached(entry: dict, threshold: tuple[float | None, float] | None) -> bool:
    """The evaluation (a :func:`point`) meets ``threshold`` (return or None, hop height);
    never without one."""
    if threshold is None:
        return False
    ret, hop = threshold
    return entry["hop"] >= hop and (ret is None or entry["return"] >= ret)


def project_run(spec: RunSpec) -> dict:
    """One run of the package on ``sys.path`` (any tree since the learning issue), its
    ``target`` the threshold (return or None, hop height; None: none, to the budget), at which
    it stops. Every evaluation is recorded, the one before the first iteration too (an agent
    that starts from a searched gait may hop before any PPO step; it is recorded at 0 s)."""
    threshold = spec.target
    config = run_config(spec.agent, spec.preset, spec.seed, spec.values, spec.budget,
                        EVAL_EVERY, EVAL_EPISODES)  # fmt: skip

    def met(evaluation: dict[str, float]) -> bool:
        return reached(point(0, 0.0, evaluation), threshold)

    try:
        from cpg_actor.training.hooks import Hook  # noqa: F401 (a tree with the loop's hooks)
    except ImportError:  # a tree before the loop's hooks
        Runner = from_tree("training.runner", "Runner")
        history: list[dict] = []

        def record(evaluation: dict[str, float]) -> None:
            history.append(point(runner.global_step, runner.train_wall, evaluation))

        def stop(evaluation: dict[str, float]) -> bool:
            record(evaluation)
            return any(reached(h, threshold) for h in history)

        runner = Runner(config, run_dir=None, tensorboard=False)
        first_evaluation = getattr(runner, "log_evaluation", None)  # the agent before training

        def log_evaluation() -> dict[str, float]:
            evaluation = first_evaluation()
            record(evaluation)
            return evaluation

        if first_evaluation is not None:  # trees that evaluate before the first update
            runner.log_evaluation = log_evaluation
        try:
            runner.learn(stop_when=stop)
        finally:
            runner.close()
        return summarize(history, threshold)
    recorder = evaluation_recorder(met)
    train(config, recorder)
    return summarize([point(s, w, e) for s, w, e in recorder.history], threshold)


class SearchSpec(NamedTuple):
    """The searches behind the start gaits of ``runs`` ((agent, preset) pairs trained with
    ``values``): one open-loop search per distinct gait, with the gait file's agent, seed and
    budget (``steps_searched``, or ``budget`` if given) on the runs' env, its gaits written to
    ``directory``. JSON-able, for a fresh process."""

    runs: list[tuple[str, str]]
    values: list[dict]
    budget: int | None
    directory: str


def search_runs(spec: SearchSpec) -> dict:
    """The open-loop search behind each distinct start gait of ``spec.runs``, rerun as the
    gait file records it (``cpg-actor train --agent open-loop-es --seed SEED --total-steps
    STEPS``; on the runs' env values). Returns ``{"AGENT PRESET": search}``: the source file,
    the search's env steps and wall time (generations, evaluations excluded), the gait it
    found (written to ``spec.directory``, the start of those runs), its deterministic
    evaluation, and how far it is from the file's gait (0.0: the same gait)."""
    searches: dict[str, dict] = {}
    by_file: dict[Path, dict] = {}
    for agent, preset in spec.runs:
        source = start_gait_file(agent, preset, spec.values)
        if source is None:
            continue
        if source not in by_file:  # (trees without start gaits never get here)
            from cpg_actor.agents.gait_file import load_gait, write_gait
            from cpg_actor.config import compose_config
            from cpg_actor.training.es_runner import ESRunner

            gait, search = recorded_search(source, spec.budget, spec.values)
            config = compose_config(None, None, search)
            config.eval_interval = 0  # evaluated once, after the search
            config.eval_episodes = EVAL_EPISODES
            runner = ESRunner(config, run_dir=None, tensorboard=False)
            try:
                runner.learn()
                evaluation = runner.run_evaluation()
                found = runner.gait()
            finally:
                runner.close()
            path = write_gait(Path(spec.directory) / f"gait_{len(by_file)}.yaml", found)
            difference = gait_difference(load_gait(path)["cpg_initial"], gait["cpg_initial"])
            by_file[source] = {
                **search_result(source, config, runner, path, difference),
                "fitness": found["fitness"],
                "return": evaluation["eval/return"],
                "hop": evaluation["eval/hop_height"],
            }
        searches[f"{agent} {preset}"] = by_file[source]
    return searches


def parse_targets(texts: list[str], option: str, form: str, parse) -> dict:
    """``AGENT=VALUE`` texts -> {agent: parse(VALUE)}; ValueError naming ``option`` and
    ``form`` for a text that does not fit."""
    targets = {}
    for text in texts:
        agent, _, value = text.partition("=")
        try:
            if not agent:
                raise ValueError
            targets[agent] = parse(value)
        except ValueError:
            raise ValueError(f"{option} {text!r}: expected {form}") from None
    return targets


def positive_steps(text: str) -> int:
    if not text.isdigit() or int(text) <= 0:
        raise ValueError(text)
    return int(text)


def return_and_hop(text: str) -> tuple[float | None, float] | None:
    """``RETURN,HOP`` (RETURN may be ``none``: hop height alone), ``HOP`` alone, or ``best``
    (no threshold: to the budget, measured to the best hop height)."""
    if text == "best":
        return None
    parts = text.split(",")
    if len(parts) == 1:
        parts = ["none", *parts]
    ret_text, hop_text = parts  # ValueError unless one or two values
    ret = None if ret_text == "none" else float(ret_text)
    hop = float(hop_text)
    if not math.isfinite(hop) or (ret is not None and not math.isfinite(ret)):
        raise ValueError(text)
    return ret, hop


def agent_targets(
    agents: list[str], budget_texts: list[str], threshold_texts: list[str]
) -> tuple[dict[str, int], dict[str, tuple[float | None, float] | None]]:
    """Each agent's step budget and threshold ((return or None, hop height), or None: to its
    best hop height within the budget): the issue's, replaced by ``--budget`` and
    ``--threshold``; ValueError for a malformed one or an agent left without a budget."""
    given_budgets = parse_targets(
        budget_texts, "--budget", "AGENT=STEPS with STEPS a positive integer", positive_steps
    )
    given_thresholds = parse_targets(
        threshold_texts,
        "--threshold",
        "AGENT=RETURN,HOP, AGENT=HOP or AGENT=best, e.g. cho2019=700,0.3",
        return_and_hop,
    )
    budgets = {**BUDGETS, **given_budgets}
    thresholds = {**THRESHOLDS, **given_thresholds}
    named = set(given_budgets) | set(given_thresholds)
    if named - set(agents):
        raise ValueError(
            f"--budget/--threshold for {', '.join(sorted(named - set(agents)))}, which is not "
            f"among --agents ({', '.join(agents)})"
        )
    for agent in agents:
        if agent not in budgets:
            raise ValueError(
                f"{agent} has no step budget of the issue (only {', '.join(BUDGETS)} do); give "
                f"one: --budget {agent}=STEPS (and --threshold {agent}=RETURN,HOP for a "
                "threshold; without one it is measured to its best hop height)"
            )
    return budgets, {agent: thresholds.get(agent) for agent in agents}


def sb3_run(
    seed: int, values: list[dict], budget: int, threshold: tuple[float | None, float] | None
) -> dict:
    """SB3's PPO with its defaults on one env, evaluated as the project's runs; it stops at
    the threshold."""
    import gymnasium as gym

    from cpg_actor.robots.hopper.plugin import ENV_ID
    from time_to_target import env_values

    physics = env_values(values)  # --set env.KEY=VALUE reaches SB3's env too
    env = gym.wrappers.RescaleAction(gym.make(ENV_ID, **physics), -1.0, 1.0)

    def numbers(result: dict) -> dict:
        return {"return": float(result["episode_return"].mean()),
                "hop": float(result["hop_height"].mean())}  # fmt: skip

    history = sb3_history(env, seed, budget, physics, EVAL_EVERY, EVAL_EPISODES, numbers,
                          lambda entry: reached(entry, threshold))  # fmt: skip
    return summarize(history, threshold)


def summarize(history: list[dict], threshold: tuple[float | None, float] | None) -> dict:
    """A run's result from its evaluations (:func:`point`): ``reached``, and ``steps``,
    ``wall``, ``return``, ``hop`` of the first evaluation that met ``threshold`` (else the
    end of the run, with the best return and its hop); ``best``: the first evaluation at the
    run's best hop height; ``near_best``: the first at ``NEAR_BEST`` of it; ``history``:
    every evaluation."""
    result: dict = {"history": history, "best": None, "near_best": None}
    hops = [h for h in history if math.isfinite(h["hop"])]
    if hops:
        best = max(hops, key=lambda h: h["hop"])  # the first of equal maxima
        near = next(h for h in hops if h["hop"] >= NEAR_BEST * best["hop"])
        result["best"] = {k: best[k] for k in ("steps", "wall", "return", "hop")}
        result["near_best"] = {k: near[k] for k in ("steps", "wall", "hop")}
    result.update(to_target(history, lambda h: reached(h, threshold)))
    hit = first_reaching(history, threshold)
    if hit is None:  # the best return, and its hop
        nothing = {"return": math.nan, "hop": math.nan}
        hit = max(history, key=lambda h: h["return"]) if history else nothing
    result.update({"hop": hit["hop"], "return": hit["return"]})
    return result


def first_reaching(history: list[dict], threshold: tuple[float | None, float] | None):
    """The first evaluation (:func:`point`) that met ``threshold``, or None."""
    return first_at_target(history, lambda h: reached(h, threshold))


def show_steps(steps: float) -> str:
    return f"{steps / 1000:.0f}k"


def show_wall(wall: float) -> str:
    return f"{wall:.0f} s"


def fmt_runs(runs: list[dict]) -> tuple[str, str, str]:
    """(seeds that reached the threshold, median env steps, median wall time), the search
    charged (the same for every seed) shown as "search + PPO = total"."""
    hits, steps, wall = over_seeds(runs)
    if not hits:
        return f"0/{len(runs)}", "not reached", "-"
    first = next(r for r in runs if r["reached"])
    return (
        f"{hits}/{len(runs)}",
        split(steps, first.get("start_steps", 0), show_steps),
        split(wall, first.get("start_wall", 0.0), show_wall),
    )


def fmt_hop(runs: list[dict]) -> str:
    """The median over seeds of each seed's best hop height."""
    hops = [r["best"]["hop"] for r in runs if r["best"] is not None]
    return f"{np.median(hops):.3f} m" if hops else "-"


def wall_ratio(reference: list[dict], ours: list[dict]) -> str:
    """Median wall time to the threshold over all seeds, reference / this tree. A seed that
    did not reach it counts as reaching it after its budget's time (a lower bound), so a
    median over such seeds is marked ">=" and a ratio with only its numerator so is too."""
    theirs, theirs_bound = censored_median_wall(reference)
    mine, mine_bound = censored_median_wall(ours)
    if mine_bound:
        return f"this tree's median seed did not reach it ({mine:.0f} s or more); no ratio"
    sign = ">= " if theirs_bound else ""
    return f"{sign}{theirs:.0f} s / {mine:.0f} s = **{sign}{theirs / mine:.2f}x**"


def describe(threshold: tuple[float | None, float] | None) -> str:
    if threshold is None:
        return "its best hop height"
    ret, hop = threshold
    return f"hop >= {hop} m" + ("" if ret is None else f" and return >= {ret:.0f}")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if answer(argv, {"--one-run": (RunSpec, project_run),
                     "--one-search": (SearchSpec, search_runs)}):  # fmt: skip
        return 0
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--agents", default="mlp,cpg-actor")
    parser.add_argument("--presets", default="paper,throughput")
    parser.add_argument("--no-sb3", action="store_true", help="skip Stable-Baselines3")
    parser.add_argument("--output", default=OUTPUT)
    parser.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
        help="a config value for this tree's runs and SB3's env, e.g. env.actuator_law=coast",
    )  # fmt: skip
    parser.add_argument(
        "--budget", dest="budgets", action="append", default=[], metavar="AGENT=STEPS",
        help="a step budget other than the issue's (mlp 500000, cpg-actor 500000; PPO steps, "
        "after any search); SB3 has mlp's (and its threshold)",
    )  # fmt: skip
    parser.add_argument(
        "--threshold", dest="thresholds", action="append", default=[],
        metavar="AGENT=RETURN,HOP", help="a threshold other than the issue's (cpg-actor: hop "
        ">= 0.45 m, any return): RETURN,HOP (RETURN may be none), HOP alone, or best (to the "
        "budget, measured to its best hop height: mlp's default)",
    )  # fmt: skip
    parser.add_argument(
        "--no-search", action="store_true",
        help="charge no search: agents that start from a gait start from the file's as it is",
    )  # fmt: skip
    parser.add_argument(
        "--search-budget", type=int, metavar="STEPS",
        help="the start gait's search with this many env steps instead of the gait file's "
        "(a quick check; the gait found is then not the file's)",
    )  # fmt: skip
    parser.add_argument("--reference-src", help="src/ of a tree to run next to this one")
    parser.add_argument(
        "--reference-set", dest="reference_overrides", action="append", default=[],
        metavar="KEY=VALUE", help="a config value for the reference tree's runs",
    )  # fmt: skip
    parser.add_argument(
        "--ceiling-steps", type=int, default=50_000,
        help="control steps per timed block of the physics ceiling (default 50000)",
    )  # fmt: skip
    args = parser.parse_args(argv)
    if args.search_budget is not None and args.search_budget <= 0:
        parser.error("--search-budget must be a positive number of env steps")

    from cpg_actor.machine import brief_openmp_spinning

    brief_openmp_spinning(os.environ)  # as the cpg-actor command runs (before torch loads)
    import torch

    from cpg_actor.config import TrainConfig, parse_override
    from cpg_actor.config.presets import preset_values
    from cpg_actor.machine import (
        cpu_model,
        cpu_times,
        git_commit,
        load_average,
        stolen_share,
        usable_cores,
    )

    agents = args.agents.split(",")
    presets = args.presets.split(",")
    try:
        budgets, thresholds = agent_targets(agents, args.budgets, args.thresholds)
    except ValueError as error:
        parser.error(str(error))
    values = [parse_override(text) for text in args.overrides]
    reference_values = [parse_override(text) for text in args.reference_overrides]
    trees = {"this tree": HERE.parent / "src"}
    if args.reference_src:
        trees["reference"] = Path(args.reference_src).resolve()
        if not (trees["reference"] / "cpg_actor").is_dir():
            parser.error(f"--reference-src {args.reference_src} holds no cpg_actor package")
    tree_values = {"this tree": values, "reference": reference_values}
    commits = {tree: git_commit(src) for tree, src in trees.items()}
    sb3 = not args.no_sb3 and "mlp" in agents
    sb3_note = ""
    if sb3 and importlib.util.find_spec("stable_baselines3") is None:
        sb3 = False
        sb3_note = (
            "Stable-Baselines3 is not installed here (`pip install stable-baselines3`), so "
            "its PPO was not run."
        )
        print(sb3_note, flush=True)
    torch.set_num_threads(1)  # SB3 here; each project run sets its own threads
    methods: list[tuple[str, object]] = []  # (label, (agent, preset, tree) or None for SB3)
    for agent in agents:
        for preset in presets:
            for tree in trees:
                suffix = "" if tree == "this tree" else f" (reference, {commits[tree]})"
                label = f"cpg-actor `{agent}`, `{preset}` preset{suffix}"
                methods.append((label, (agent, preset, tree)))
        if agent == "mlp" and sb3:
            methods.append(("Stable-Baselines3 PPO, defaults (MLP)", None))
    results: dict[str, list[dict]] = {label: [] for label, _ in methods}
    # (agent, preset, tree) -> the search of its start gait (None: none charged)
    searches: dict[tuple[str, str, str], dict | None] = {}
    with tempfile.TemporaryDirectory(prefix="time_to_hop_gaits_") as gait_dir:
        # each start gait's search once, before the seeds: every seed starts from its gait
        for tree, src in trees.items():
            pairs = [(agent, preset) for agent in agents for preset in presets]
            found: dict[str, dict] = {}
            if not args.no_search:
                directory = Path(gait_dir) / tree.replace(" ", "_")
                directory.mkdir()
                spec = SearchSpec(pairs, tree_values[tree], args.search_budget, str(directory))
                found = in_fresh_process(__file__, "--one-search", spec, src)
            for agent, preset in pairs:
                searches[agent, preset, tree] = found.get(f"{agent} {preset}")
                if searches[agent, preset, tree] is not None:
                    print(f"search for {agent} {preset} ({tree}): {found[f'{agent} {preset}']}")
        for seed in range(args.seeds):
            for label, spec in methods:
                cpu_start = cpu_times()
                if spec is None:
                    run = sb3_run(seed, values, budgets["mlp"], thresholds["mlp"])
                    search = None
                else:
                    agent, preset, tree = spec
                    search = searches[spec]
                    run_values = list(tree_values[tree])
                    if search is not None:  # start from the gait this run's search found
                        run_values.append({"agent_config": {"start_gait": search["gait"]}})
                    run_spec = RunSpec(
                        agent, preset, seed, run_values, budgets[agent], thresholds[agent]
                    )
                    run = in_fresh_process(__file__, "--one-run", run_spec, trees[tree])
                run["stolen"] = stolen_share(cpu_start, cpu_times())  # a neighbour's load
                if search is not None:
                    run["start_steps"], run["start_wall"] = search["steps"], search["wall"]
                results[label].append(run)
                brief = {k: v for k, v in run.items() if k != "history"}
                print(f"seed {seed} {label}: {brief}", flush=True)
    sizes = {1} | {
        TrainConfig().num_envs if p == "paper" else preset_values(p).get("num_envs", 16)
        for p in presets
    }
    ceilings = {n: hopper_ceiling(n, args.ceiling_steps) for n in sorted(sizes)}
    command = (
        f"python benchmarks/time_to_hop.py --seeds {args.seeds} --agents {args.agents} "
        f"--presets {args.presets}"
        + (" --no-sb3" if args.no_sb3 else "")
        + (" --no-search" if args.no_search else "")
        + (f" --search-budget {args.search_budget}" if args.search_budget else "")
        + "".join(f" --budget {b}" for b in args.budgets)
        + "".join(f" --threshold {t}" for t in args.thresholds)
        + "".join(f" --set {o}" for o in args.overrides)
        + (" --reference-src REF/src" if args.reference_src else "")
        + "".join(f" --reference-set {o}" for o in args.reference_overrides)
        + (f" --output {args.output}" if args.output != OUTPUT else "")
    )
    code = f"this tree at commit {commits['this tree']}" + (
        f", REF at commit {commits['reference']}" if args.reference_src else ""
    )
    text = report(
        methods, results, searches, agents, budgets, thresholds, sb3, sb3_note, ceilings,
        f"Measured {datetime.date.today().isoformat()} by `{command}` ({code}) on "
        f"{cpu_model()}, {usable_cores()} usable cores (load {load_average()} at the end), "
        f"torch {torch.__version__}; each project run and each search in a fresh process, "
        "one at a time.",
    )  # fmt: skip
    Path(args.output).write_text(text)
    print(text)
    return 0


def report(
    methods: list[tuple[str, object]],
    results: dict[str, list[dict]],
    searches: dict[tuple[str, str, str], dict | None],
    agents: list[str],
    budgets: dict[str, int],
    thresholds: dict[str, tuple[float | None, float] | None],
    sb3: bool,
    sb3_note: str,
    ceilings: dict[int, float],
    measured: str,
) -> str:
    """The markdown report: the searches, the methods with a threshold (time to it), the
    methods without (time to their best hop height), the reference ratios, the ceiling."""

    def threshold_of(spec) -> tuple[float | None, float] | None:
        return thresholds["mlp"] if spec is None else thresholds[spec[0]]

    def budget_of(spec) -> int:
        return budgets["mlp"] if spec is None else budgets[spec[0]]

    targets = "; ".join(
        f"`{agent}`{' and SB3' if agent == 'mlp' and sb3 else ''}: {describe(thresholds[agent])} "
        f"within {budgets[agent]:,} steps"
        for agent in agents
    )
    lines = [
        "# Time to hop: wall-clock time to a deterministic hop height",
        "",
        measured,
        "",
        f"Targets ({targets}) on the mean over {EVAL_EPISODES} deterministic episodes, "
        f"evaluated every {EVAL_EVERY:,} env steps and before the first update. Time is "
        "training wall time without the evaluations (compilation included). An agent that "
        "starts from a searched gait (`agent_config.start_gait`) is charged its search: the "
        "open-loop search that made the gait is rerun in this run, once per gait (all seeds "
        "start from the gait it finds), and its env steps and wall time are added to each "
        "seed's (shown as search + PPO = total; the budget counts PPO steps). CPU stolen: per "
        "seed, the share of the machine's CPU time that its hypervisor gave to something else "
        "during the run (`steal` in `/proc/stat`).",
    ]
    if sb3_note:
        lines += ["", sb3_note]
    shown: dict[str, list[str]] = {}
    for (agent, preset, tree), search in searches.items():
        if search is not None:
            shown.setdefault(json.dumps(search, sort_keys=True), []).append(
                f"`{agent}` `{preset}`" + ("" if tree == "this tree" else " (reference)")
            )
    if shown:
        lines += [
            "",
            "## The start gaits' searches",
            "",
            "| gait file | search | env steps | wall time | fitness | deterministic return, "
            "hop | the gait found against the file's | charged to |",
            "| --- | --- | ---: | ---: | ---: | ---: | --- | --- |",
        ]
        for key, users in shown.items():
            search = json.loads(key)
            difference = search["difference"]
            against = (
                "**the same gait**"
                if difference == 0
                else f"differs (largest relative difference {difference:.2g})"
            )
            lines.append(
                f"| `{Path(search['source']).name}` | `{search['agent']}`, seed "
                f"{search['seed']}, budget {search['budget']:,} | {search['steps']:,} | "
                f"{search['wall']:.0f} s | {search['fitness']:.0f} | {search['return']:.0f}, "
                f"{search['hop']:.3f} m | {against} | {', '.join(users)} |"
            )
    timed = [(label, spec) for label, spec in methods if threshold_of(spec) is not None]
    best = [(label, spec) for label, spec in methods if threshold_of(spec) is None]
    if timed:
        lines += [
            "",
            "## Time to the threshold",
            "",
            "Env steps and wall time: medians over the seeds that reached it. Best hop: the "
            "median over seeds of each seed's best evaluation (until it stopped).",
            "",
            "| method | target | seeds that reached it | env steps | wall time | best hop "
            "| per seed (PPO) | CPU stolen |",
            "| --- | --- | ---: | ---: | ---: | ---: | --- | ---: |",
        ]
        for label, spec in timed:
            runs = results[label]
            hit, steps, wall = fmt_runs(runs)
            per_seed = "; ".join(
                f"{r['steps'] / 1000:.0f}k, {r['wall']:.0f} s (hop {r['hop']:.2f} m)"
                if r["reached"]
                else f"best hop {r['best']['hop'] if r['best'] else math.nan:.2f} m, best "
                f"return {r['return']:.0f}, budget in {r['wall']:.0f} s"
                for r in runs
            )
            lines.append(
                f"| {label} | {describe(threshold_of(spec))} | {hit} | {steps} | {wall} | "
                f"{fmt_hop(runs)} | {per_seed} | {fmt_stolen(runs)} |"
            )
    if best:
        goals = sorted({thresholds[a] for a in agents if thresholds[a] is not None}, key=str)
        lines += [
            "",
            "## Time to its own best hop height",
            "",
            "Each seed trains to its budget; its best hop height is its best evaluation, reached "
            f"first after the steps and time given; near it: the first evaluation at "
            f"{NEAR_BEST:.0%} of it. Medians over seeds."
            + (" Also when it first met the other agents' targets." if goals else ""),
            "",
            "| method | budget | best hop | env steps to it | wall time to it | near it: steps, "
            "time | "
            + "".join(f"{describe(goal)}: seeds, median time | " for goal in goals)
            + "per seed | CPU stolen |",
            "| --- | ---: | ---: | ---: | ---: | ---: | " + "---: | " * len(goals) + "--- | ---: |",
        ]
        for label, spec in best:
            runs = [r for r in results[label] if r["best"] is not None]
            if not runs:
                lines.append(f"| {label} | {budget_of(spec):,} | no evaluation |")
                continue
            bests = [r["best"] for r in runs]
            nears = [r["near_best"] for r in runs]
            cells = [
                f"{budget_of(spec):,}",
                fmt_hop(runs),
                f"{np.median([b['steps'] for b in bests]) / 1000:.0f}k",
                f"{np.median([b['wall'] for b in bests]):.0f} s",
                f"{np.median([n['steps'] for n in nears]) / 1000:.0f}k, "
                f"{np.median([n['wall'] for n in nears]):.0f} s",
            ]
            for goal in goals:
                hits = [first_reaching(r["history"], goal) for r in runs]
                hits = [h for h in hits if h is not None]
                cells.append(
                    f"{len(hits)}/{len(runs)}, {np.median([h['wall'] for h in hits]):.0f} s"
                    if hits
                    else f"0/{len(runs)}"
                )
            cells.append(
                "; ".join(
                    f"{b['hop']:.3f} m (return {b['return']:.0f}) at {b['steps'] / 1000:.0f}k, "
                    f"{b['wall']:.0f} s"
                    for b in bests
                )
            )
            cells.append(fmt_stolen(results[label]))
            lines.append(f"| {label} | " + " | ".join(cells) + " |")
    references = [spec for _, spec in timed if spec is not None and spec[2] == "reference"]
    if references:
        lines += ["", "Median wall time to the threshold, reference / this tree:", ""]
        by_spec = {spec: results[label] for label, spec in methods if spec is not None}
        for agent, preset, _ in references:
            lines.append(
                f"- `{agent}`, `{preset}` preset: "
                + wall_ratio(
                    by_spec[agent, preset, "reference"], by_spec[agent, preset, "this tree"]
                )
            )
    lines += [
        "",
        "Physics ceiling in the same run (`mujoco.rollout`, 10 substeps per control step, "
        "constant torques): "
        + ", ".join(f"{v:,.0f} control steps/s at N={n}" for n, v in ceilings.items())
        + ". The paper preset steps 16 envs, the throughput preset 256, SB3 1, the search "
        "16 (its population).",
    ]
    return "\n".join(lines) + "\n"


def fmt_stolen(runs: list[dict]) -> str:
    return ", ".join(f"{r['stolen']:.0%}" if math.isfinite(r["stolen"]) else "-" for r in runs)


if __name__ == "__main__":
    raise SystemExit(main())
