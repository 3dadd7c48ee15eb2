"""Wall-clock time and env steps until a deterministic evaluation reaches a threshold, per
agent and preset, side by side with Stable-Baselines3's PPO (defaults) in the same run.

    python benchmarks/time_to_hop.py [--seeds 3] [--output benchmarks/results/time_to_hop.md]

What a user waits for is a good policy, not steps per second. Every method is evaluated the
same way (:func:`cpg_actor.evaluation.evaluate`: the mean action, 5 episodes on envs of their
own, the same reset seed) every ``EVAL_EVERY`` env steps; a method reaches a threshold when one
evaluation has a mean return >= R and a mean hop height >= H. Time is training wall time,
evaluations excluded. Runs stop at the threshold or at their step budget, one at a time (no
two measurements share the CPU). SB3 (``pip install stable-baselines3``) runs stock: PPO
``MlpPolicy`` with its defaults (Baselines' ppo2 numbers) on the registered env
``cpg_actor/AnymalHopper-v0`` with actions rescaled to [-1, 1] and no VecNormalize. The
physics ceiling (``mujoco.rollout`` on the project's MJCF, the same N envs) is measured in the
same run (``benchmarks/env_throughput.py``).

Each of the project's runs is a fresh process (this script with ``--one-run``) with
``PYTHONPATH`` set to a tree's ``src``. ``--reference-src REF/src`` also runs every agent and
preset with the package of another tree (e.g. the commit before a redesign), taking turns with
this tree's runs, so the two are measured on the same machine in the same run; ``--set``
applies to this tree's runs and SB3's env, ``--reference-set`` to the reference's (a
reference older than a config key needs none: ``env.actuator_law=coast`` here is the only law
before 26 Nov 2026). The ratio of the two trees' median wall times counts a seed that missed
the threshold as later than its whole budget, so that median is a lower bound (">=");
``--budget AGENT=STEPS`` gives an agent another budget (the threshold stays);
``--threshold AGENT=RETURN,HOP`` another threshold, or one to an agent the learning issue set
none for (``cpg-actor-open-loop``, the Cho et al. agents: they need both). Each run also
records the share of the machine's CPU time its hypervisor took meanwhile
(:func:`cpg_actor.machine.cpu_times`).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import sys
import time
from pathlib import Path
from types import SimpleNamespace
from typing import NamedTuple

import numpy as np

# The project's imports are in the functions: a run with --one-run imports the package of the
# tree its PYTHONPATH names, which may be older than this script.
HERE = Path(__file__).resolve().parent

EVAL_EVERY = 10_240  # env steps between evaluations (5 iterations of 2,048 steps)
EVAL_EPISODES = 5
# (return, hop height) thresholds and step budgets: the targets of the learning issue
THRESHOLDS = {"mlp": (800.0, 0.28), "cpg-actor": (600.0, 0.30)}
BUDGETS = {"mlp": 300_000, "cpg-actor": 500_000}


def reached(evaluation: dict[str, float], threshold: tuple[float, float]) -> bool:
    return (
        evaluation["eval/return"] >= threshold[0] and evaluation["eval/hop_height"] >= threshold[1]
    )


class RunSpec(NamedTuple):
    """One project run: ``agent`` trained with ``preset``, then each of ``values`` (nested
    config mappings), from ``seed`` until ``threshold`` (return, hop height) or ``budget``
    env steps. JSON-able as a dict, for a run in a fresh process."""

    agent: str
    preset: str
    seed: int
    values: list[dict]
    budget: int
    threshold: tuple[float, float]


def project_run(spec: RunSpec) -> dict:
    """One run of the package on ``sys.path`` (any tree since the learning issue)."""
    agent, preset, seed, values, budget, threshold = spec
    from cpg_actor.agents import get_agent_spec
    from cpg_actor.config import TrainConfig, apply_dict
    from cpg_actor.presets import preset_values
    from cpg_actor.runner import Runner

    config = TrainConfig()
    # the agent's tuned settings first, as `cpg-actor train` composes them (trees without
    # per-agent defaults have none)
    spec = get_agent_spec(agent)
    apply_dict(config, getattr(spec, "defaults", {}).get(config.robot, {}), prefix="")
    apply_dict(config, preset_values(preset), prefix="")
    for mapping in values:
        apply_dict(config, mapping, prefix="")
    config.agent, config.seed, config.total_steps = agent, seed, budget
    config.eval_interval = max(1, round(EVAL_EVERY / config.steps_per_iteration))
    config.eval_episodes = EVAL_EPISODES
    runner = Runner(config, run_dir=None, tensorboard=False)
    history: list[tuple[int, float, float, float]] = []

    def stop(evaluation: dict[str, float]) -> bool:
        history.append(
            (
                runner.global_step,
                runner.train_wall,
                evaluation["eval/return"],
                evaluation["eval/hop_height"],
            )
        )
        return reached(evaluation, threshold)

    try:
        runner.learn(stop_when=stop)
    finally:
        runner.close()
    return summarize(history, threshold)


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


def return_and_hop(text: str) -> tuple[float, float]:
    ret, hop = (float(v) for v in text.split(","))  # ValueError unless two numbers
    if not (math.isfinite(ret) and math.isfinite(hop)):
        raise ValueError(text)
    return ret, hop


def agent_targets(
    agents: list[str], budget_texts: list[str], threshold_texts: list[str]
) -> tuple[dict[str, int], dict[str, tuple[float, float]]]:
    """Each agent's step budget and (return, hop height) threshold: the learning issue's,
    replaced by ``--budget`` and ``--threshold``; ValueError for a malformed one or an agent
    left without either."""
    given_budgets = parse_targets(
        budget_texts, "--budget", "AGENT=STEPS with STEPS a positive integer", positive_steps
    )
    given_thresholds = parse_targets(
        threshold_texts,
        "--threshold",
        "AGENT=RETURN,HOP with two numbers, e.g. cho2019=700,0.3",
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
        if agent not in budgets or agent not in thresholds:
            raise ValueError(
                f"{agent} has no threshold or step budget of the learning issue (only "
                f"{', '.join(THRESHOLDS)} do); give both: --threshold {agent}=RETURN,HOP "
                f"--budget {agent}=STEPS"
            )
    return budgets, thresholds


def tree_run(src: Path, spec: RunSpec) -> dict:
    """:func:`project_run` in a fresh process with the package in ``src``."""
    from bench_report import json_from_tree

    return json_from_tree(src, [__file__, "--one-run", json.dumps(spec._asdict())])


class SB3Policy:
    """An SB3 model behind the :class:`cpg_actor.policy.Policy` calls :func:`evaluate` makes."""

    def __init__(self, model, low: np.ndarray, high: np.ndarray) -> None:
        self.model, self.low, self.high = model, low, high

    def reset(self, num_envs: int) -> None:
        pass

    def act(self, obs: np.ndarray, deterministic: bool = True):
        import torch

        from cpg_actor.policy import PolicyStep

        action, _ = self.model.predict(np.asarray(obs), deterministic=True)  # in [-1, 1]
        desired = self.low + (np.asarray(action) + 1.0) * (self.high - self.low) / 2.0
        agent = SimpleNamespace(extras={})
        return PolicyStep(desired.astype(np.float32), torch.as_tensor(obs), torch.zeros(0), agent)


def sb3_run(seed: int, values: list[dict], budget: int, threshold: tuple[float, float]) -> dict:
    import gymnasium as gym
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback

    from cpg_actor.envs import ENV_ID, HopperConfig, HopperVectorEnv
    from cpg_actor.evaluation import evaluate
    from cpg_actor.runner import EVAL_SEED_KEY, derived_seed

    env_values = {}  # --set env.KEY=VALUE reaches SB3's env too
    for mapping in values:
        env_values.update(mapping.get("env", {}))
    env = gym.wrappers.RescaleAction(gym.make(ENV_ID, **env_values), -1.0, 1.0)
    eval_env = HopperVectorEnv(EVAL_EPISODES, HopperConfig(**env_values))
    low, high = env.unwrapped.action_space.low, env.unwrapped.action_space.high
    history: list[tuple[int, float, float, float]] = []
    clock = {"start": 0.0, "eval": 0.0}

    class Evaluate(BaseCallback):
        def _on_training_start(self) -> None:
            clock["start"] = time.perf_counter()

        def _on_step(self) -> bool:
            if self.num_timesteps % EVAL_EVERY:
                return True
            start = time.perf_counter()
            result = evaluate(
                SB3Policy(self.model, low, high),
                eval_env,
                seed=derived_seed(seed, EVAL_SEED_KEY),
                control_dt=0.01,
                max_steps=500,
                traces=False,
            )
            clock["eval"] += time.perf_counter() - start
            wall = time.perf_counter() - clock["start"] - clock["eval"]
            ret, hop = float(result["episode_return"].mean()), float(result["hop_height"].mean())
            history.append((self.num_timesteps, wall, ret, hop))
            return not reached({"eval/return": ret, "eval/hop_height": hop}, threshold)

    model = PPO("MlpPolicy", env, seed=seed, device="cpu", verbose=0)
    try:
        model.learn(total_timesteps=budget, callback=Evaluate())
    finally:
        env.close()
        eval_env.close()
    return summarize(history, threshold)


def summarize(history, threshold) -> dict:
    for step, wall, ret, hop in history:
        if ret >= threshold[0] and hop >= threshold[1]:
            return {"reached": True, "steps": step, "wall": wall, "return": ret, "hop": hop}
    best = max(history, key=lambda h: h[2]) if history else (0, math.nan, math.nan, math.nan)
    last = history[-1] if history else best
    return {"reached": False, "steps": last[0], "wall": last[1], "return": best[2], "hop": best[3]}


def ceiling(num_envs: int) -> float:
    sys.path.insert(0, str(Path(__file__).parent))
    from env_throughput import bench_size

    return bench_size("mujoco", num_envs, repeats=2, budget=50_000)["rollout"]


def fmt_runs(runs: list[dict]) -> tuple[str, str, str]:
    hits = [r for r in runs if r["reached"]]
    if not hits:
        return f"0/{len(runs)}", "not reached", "-"
    steps = np.median([r["steps"] for r in hits])
    return f"{len(hits)}/{len(runs)}", f"{steps / 1000:.0f}k", f"{median_wall(runs):.0f} s"


def one_run(text: str) -> int:
    """``--one-run``: a :func:`project_run` from its JSON spec; prints its result as JSON."""
    spec = RunSpec(**json.loads(text))
    print(json.dumps(project_run(spec._replace(threshold=tuple(spec.threshold)))))
    return 0


def median_wall(runs: list[dict]) -> float:
    hits = [r["wall"] for r in runs if r["reached"]]
    return float(np.median(hits)) if hits else math.nan


def wall_ratio(reference: list[dict], ours: list[dict]) -> str:
    """Median wall time to the threshold over all seeds, reference / this tree. A seed that
    did not reach it counts as reaching it after its budget's time (a lower bound), so a
    median over such seeds is marked ">=" and a ratio with only its numerator so is too."""

    def median(runs: list[dict]) -> tuple[float, bool]:  # (seconds, a lower bound only)
        mid = float(np.median([r["wall"] if r["reached"] else math.inf for r in runs]))
        if math.isfinite(mid):
            return mid, False
        bounds = [r["wall"] for r in runs]
        return float(np.median(bounds)), True

    theirs, theirs_bound = median(reference)
    mine, mine_bound = median(ours)
    if mine_bound:
        return f"this tree's median seed did not reach it ({mine:.0f} s or more); no ratio"
    sign = ">= " if theirs_bound else ""
    return f"{sign}{theirs:.0f} s / {mine:.0f} s = **{sign}{theirs / mine:.2f}x**"


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--one-run"]:
        return one_run(argv[1])
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--agents", default="mlp,cpg-actor")
    parser.add_argument("--presets", default="paper,throughput")
    parser.add_argument("--no-sb3", action="store_true", help="skip Stable-Baselines3")
    parser.add_argument("--output", default="benchmarks/results/time_to_hop.md")
    parser.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
        help="a config value for this tree's runs and SB3's env, e.g. env.actuator_law=coast",
    )  # fmt: skip
    parser.add_argument(
        "--budget", dest="budgets", action="append", default=[], metavar="AGENT=STEPS",
        help="a step budget other than the learning issue's (mlp 300000, cpg-actor 500000); "
        "SB3 has mlp's (and its threshold)",
    )  # fmt: skip
    parser.add_argument(
        "--threshold", dest="thresholds", action="append", default=[],
        metavar="AGENT=RETURN,HOP", help="a threshold other than the learning issue's (mlp "
        "800,0.28; cpg-actor 600,0.3), or one for another agent (with --budget)",
    )  # fmt: skip
    parser.add_argument("--reference-src", help="src/ of a tree to run next to this one")
    parser.add_argument(
        "--reference-set", dest="reference_overrides", action="append", default=[],
        metavar="KEY=VALUE", help="a config value for the reference tree's runs",
    )  # fmt: skip
    args = parser.parse_args(argv)

    from cpg_actor.machine import brief_openmp_spinning

    brief_openmp_spinning(os.environ)  # as the cpg-actor command runs (before torch loads)
    import torch

    from cpg_actor.config import TrainConfig, parse_override
    from cpg_actor.machine import (
        cpu_model,
        cpu_times,
        git_commit,
        load_average,
        stolen_share,
        usable_cores,
    )
    from cpg_actor.presets import preset_values

    agents = args.agents.split(",")
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
    commits = {tree: git_commit(src) for tree, src in trees.items()}
    torch.set_num_threads(1)  # SB3 here; each project run sets its own threads
    methods: list[tuple[str, object]] = []  # (label, (agent, preset, tree) or None for SB3)
    for agent in agents:
        for preset in args.presets.split(","):
            for tree in trees:
                suffix = "" if tree == "this tree" else f" (reference, {commits[tree]})"
                label = f"cpg-actor `{agent}`, `{preset}` preset{suffix}"
                methods.append((label, (agent, preset, tree)))
        if agent == "mlp" and not args.no_sb3:
            methods.append(("Stable-Baselines3 PPO, defaults (MLP)", None))
    results: dict[str, list[dict]] = {label: [] for label, _ in methods}
    for seed in range(args.seeds):
        for label, spec in methods:
            cpu_start = cpu_times()
            if spec is None:
                run = sb3_run(seed, values, budgets["mlp"], thresholds["mlp"])
            else:
                agent, preset, tree = spec
                tree_values = values if tree == "this tree" else reference_values
                run_spec = RunSpec(
                    agent, preset, seed, tree_values, budgets[agent], thresholds[agent]
                )
                run = tree_run(trees[tree], run_spec)
            run["stolen"] = stolen_share(cpu_start, cpu_times())  # a neighbour's load
            results[label].append(run)
            print(f"seed {seed} {label}: {run}", flush=True)
    sizes = {1} | {
        TrainConfig().num_envs if p == "paper" else preset_values(p).get("num_envs", 16)
        for p in args.presets.split(",")
    }
    ceilings = {n: ceiling(n) for n in sorted(sizes)}
    command = (
        f"python benchmarks/time_to_hop.py --seeds {args.seeds} --agents {args.agents} "
        f"--presets {args.presets}"
        + (" --no-sb3" if args.no_sb3 else "")
        + "".join(f" --budget {b}" for b in args.budgets)
        + "".join(f" --threshold {t}" for t in args.thresholds)
        + "".join(f" --set {o}" for o in args.overrides)
        + (" --reference-src REF/src" if args.reference_src else "")
        + "".join(f" --reference-set {o}" for o in args.reference_overrides)
    )
    code = f"this tree at commit {commits['this tree']}" + (
        f", REF at commit {commits['reference']}" if args.reference_src else ""
    )
    lines = [
        "# Time to hop: wall-clock time until a deterministic evaluation reaches a threshold",
        "",
        f"Measured {datetime.date.today().isoformat()} by `{command}` ({code}) on "
        f"{cpu_model()}, {usable_cores()} usable cores (load {load_average()} at the end), "
        f"torch {torch.__version__}; each project run in a fresh process, one at a time.",
        "",
        f"Threshold: mean return and hop height over {EVAL_EPISODES} deterministic episodes, "
        f"evaluated every {EVAL_EVERY:,} env steps ("
        + "; ".join(
            f"{agent}{' and SB3' if agent == 'mlp' and not args.no_sb3 else ''}: return >= "
            f"{thresholds[agent][0]:.0f} and hop >= {thresholds[agent][1]} m within "
            f"{budgets[agent]:,} steps"
            for agent in agents
        )
        + "). "
        "Steps and time are medians over the seeds that reached it; time is training wall "
        "time without the evaluations (compilation included). CPU stolen: per seed, the "
        "share of the machine's CPU time that its hypervisor gave to something else during "
        "the run (`steal` in `/proc/stat`; a neighbour's load on a shared host).",
        "",
        "| method | seeds that reached it | env steps | wall time | per seed | CPU stolen |",
        "| --- | ---: | ---: | ---: | --- | ---: |",
    ]
    for label, _ in methods:
        runs = results[label]
        hit, steps, wall = fmt_runs(runs)
        per_seed = "; ".join(
            f"{r['steps'] / 1000:.0f}k, {r['wall']:.0f} s"
            if r["reached"]
            else f"best {r['return']:.0f} (hop {r['hop']:.2f} m), budget in {r['wall']:.0f} s"
            for r in runs
        )
        stolen = ", ".join(
            f"{r['stolen']:.0%}" if math.isfinite(r["stolen"]) else "-" for r in runs
        )
        lines.append(f"| {label} | {hit} | {steps} | {wall} | {per_seed} | {stolen} |")
    if args.reference_src:
        lines += ["", "Median wall time to the threshold, reference / this tree:", ""]
        by_spec = {spec: results[label] for label, spec in methods if spec is not None}
        for agent in agents:
            for preset in args.presets.split(","):
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
        + ". The paper preset steps 16 envs, the throughput preset 256, SB3 1.",
    ]
    text = "\n".join(lines) + "\n"
    Path(args.output).write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
