"""What the time-to-a-target benchmarks share (``time_to_hop.py``, ``time_to_quality.py``,
``time_to_walk.py``): a run's config as ``cpg-actor train`` composes it and its evaluation
cadence; its training with every evaluation recorded and its start charged; a run in a fresh
process from a JSON-able spec; the time to a target from a run's evaluations and over seeds;
the start gait's search rerun; Stable-Baselines3's PPO evaluated as the project's runs.

A run's time to its target is that of its first evaluation that met it. A run that never met
it is censored at its end: ``reached`` False, its ``steps`` and ``wall`` those of its last
evaluation. What a run's start cost (a searched gait, a warm start) is charged on top:
``start_steps`` and ``start_wall``; :func:`total_steps` and :func:`total_wall` add it.

These are the studies' helpers (the design's ``studies/``); they stay in ``benchmarks/`` until
that package exists. The project's package is imported inside the functions: time_to_hop runs
its runs with the package of another tree (``--reference-src``), which may be older than
this module.
"""

from __future__ import annotations

import json
import math
import sys
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from types import SimpleNamespace
from typing import Any, NamedTuple

import numpy as np

HERE = Path(__file__).resolve().parent


# -- a run's config --------------------------------------------------------------------------
def from_tree(module: str, name: str):
    """``name`` from ``cpg_actor.<module>``, or from its flat path in a tree from before the
    package's folders (``training.runner`` was ``runner``, ``config.presets`` ``presets``)."""
    import importlib

    try:
        return getattr(importlib.import_module(f"cpg_actor.{module}"), name)
    except ImportError:
        flat = module.rsplit(".", 1)[-1]
        return getattr(importlib.import_module(f"cpg_actor.{flat}"), name)


def agent_defaults(agent: str, robot: str) -> dict:
    """The agent's tuned settings on ``robot``: ``Robot.agent_defaults`` in trees with robot
    plug-ins, ``AgentSpec.defaults[robot]`` in the trees before them, else none."""
    from cpg_actor.agents import get_agent_spec

    try:
        from cpg_actor.robots.registry import ROBOTS
    except ImportError:  # a tree from before the robot registry
        ROBOTS = {}
    if robot in ROBOTS and hasattr(ROBOTS[robot], "agent_defaults"):
        return dict(ROBOTS[robot].agent_defaults.get(agent, {}))
    return dict(getattr(get_agent_spec(agent), "defaults", {}).get(robot, {}))


def compose(agent: str, preset: str, values: list[dict]):
    """The run's :class:`TrainConfig` as ``cpg-actor train`` composes it: the agent's tuned
    settings on the robot (trees without per-agent defaults have none), the preset, then
    ``values`` (nested config mappings, in order)."""
    from cpg_actor.config import TrainConfig, apply_dict

    preset_values = from_tree("config.presets", "preset_values")

    def composed(defaults: dict) -> TrainConfig:
        config = TrainConfig()
        config.agent = agent
        apply_dict(config, defaults, prefix="")
        apply_dict(config, preset_values(preset), prefix="")
        for mapping in values:
            apply_dict(config, mapping, prefix="")
        return config

    config = composed({})  # which robot: its defaults for the agent come first
    return composed(agent_defaults(agent, config.robot))


class RunSpec(NamedTuple):
    """One project run: ``agent`` with ``preset`` and ``values`` (nested config mappings, in
    order; a start gait among them), from ``seed`` for ``budget`` env steps of its own, until
    its ``target`` (the benchmark's, JSON-able; None: none) if ``stop``, else to its budget.
    JSON-able as a dict, for a run in a fresh process (:func:`in_fresh_process`). (A run of
    ``time_to_walk.py`` has its own: a quadruped's task, its evaluation, its ceiling.)"""

    agent: str
    preset: str
    seed: int
    values: list[dict]
    budget: int
    target: Any
    stop: bool = True


def evaluate_every(config, every: int, episodes: int | None = None) -> None:
    """Evaluate ``config``'s run every ``every`` env steps, rounded to whole iterations (at
    least one; the open-loop search's iteration is a generation), on ``episodes`` episodes
    (None: as the config says)."""
    if config.agent == "open-loop-es":
        from cpg_actor.agents.open_loop_es import generation_steps

        per_iteration = generation_steps(config)
    else:
        per_iteration = config.steps_per_iteration
    config.eval_interval = max(1, round(every / per_iteration))
    if episodes is not None:
        config.eval_episodes = episodes


def run_config(agent: str, preset: str, seed: int, values: list[dict], budget: int,
               every: int, episodes: int):  # fmt: skip
    """A run's config: :func:`compose`'d, from ``seed`` for ``budget`` env steps, evaluated
    every ``every`` env steps on ``episodes`` episodes."""
    config = compose(agent, preset, values)
    config.agent, config.seed, config.total_steps = agent, seed, budget
    evaluate_every(config, every, episodes)
    return config


def env_values(values: Iterable[dict]) -> dict:
    """The ``env`` values of nested config mappings (``--set env.KEY=VALUE``), later ones
    winning: the runs' physics, for an env built outside a run (a search's, SB3's)."""
    merged: dict = {}
    for mapping in values:
        merged.update(mapping.get("env", {}))
    return merged


# -- training a run, every evaluation recorded ------------------------------------------------
def evaluation_recorder(stop: Callable[[dict[str, float]], bool] | None = None):
    """A training-loop hook (:class:`cpg_actor.training.hooks.Hook`, for ``Runner(hooks=...)``)
    that records every evaluation of a run in its ``history``, as ``(env steps, training wall
    time, evaluation)`` at it: the one before the first update (at 0 s; an agent that starts
    from a gait or a warm start may already be there) and the periodic ones. With ``stop``, the
    run stops after the first iteration by which an evaluation met it (a first evaluation
    that met it stops the run after one iteration, still recorded at its 0 s); ``stop`` is
    called with the evaluation already in ``history``. It reads the runner and changes
    nothing it trains."""
    from cpg_actor.training.hooks import Hook

    class Recorder(Hook):
        def __init__(self) -> None:
            self.history: list[tuple[int, float, dict[str, float]]] = []
            self.met = False

        def add(self, runner, evaluation: dict[str, float]) -> None:
            self.history.append((runner.global_step, runner.train_wall, dict(evaluation)))
            self.met = self.met or (stop is not None and bool(stop(evaluation)))

        def start(self, runner, fresh: bool) -> None:
            if runner.last_evaluation is not None:  # the evaluation hook's, before the first
                self.add(runner, runner.last_evaluation)

        def iteration(self, runner, it) -> None:
            if it.evaluation is not None:
                self.add(runner, it.evaluation)
            it.stop = it.stop or self.met

    return Recorder()


def charged_warm_start(runner, config) -> dict:
    """What ``runner``'s warm start costs, charged to it: ``{"steps", "wall"}``, 0 for an agent
    without one. Its env steps (``warm_start.rollout_steps`` control steps on each of
    ``num_envs`` envs) are known now; its wall time fills in as :meth:`Runner.learn` runs it
    (``run_warm_start`` is wrapped in a timer)."""
    cost = {"steps": 0, "wall": 0.0}
    if getattr(getattr(runner, "spec", None), "warm_start", None) is None:
        return cost
    fit = runner.run_warm_start

    def timed_warm_start() -> list[float]:
        begin = time.perf_counter()
        try:
            return fit()
        finally:
            cost["wall"] += time.perf_counter() - begin

    runner.run_warm_start = timed_warm_start  # what learn() calls before PPO
    cost["steps"] = config.warm_start.rollout_steps * config.num_envs
    return cost


def train(config, recorder, hooks: Iterable = (), setup: Callable | None = None):
    """Train ``config`` in this process (PPO, or the open-loop search for an agent trained by
    it) with ``recorder`` (:func:`evaluation_recorder`) and ``hooks``, its warm start timed;
    ``setup(runner)`` before it learns. Returns ``(warm start's {"steps", "wall"}, runner)``,
    the runner closed; the evaluations are in ``recorder.history``."""
    from cpg_actor.agents import get_agent_spec

    if getattr(get_agent_spec(config.agent), "trainer", "ppo") == "es":
        from cpg_actor.training.es_runner import ESRunner

        runner = ESRunner(config, run_dir=None, tensorboard=False)
        runner.hooks += [recorder, *hooks]
    else:
        Runner = from_tree("training.runner", "Runner")
        runner = Runner(config, run_dir=None, tensorboard=False, hooks=[recorder, *hooks])
    warm = charged_warm_start(runner, config)
    if setup is not None:
        setup(runner)
    try:
        runner.learn()
    finally:
        runner.close()
    return warm, runner


# -- a run in a fresh process -------------------------------------------------------------------
def in_fresh_process(
    script: str | Path, flag: str, spec: NamedTuple, src: str | Path = HERE.parent / "src",
    show_stderr: bool = False,
) -> dict:  # fmt: skip
    """``script flag SPEC-AS-JSON`` in a fresh process with the package in ``src`` (this
    tree's by default); the JSON it prints last (:func:`answer`)."""
    from bench_report import json_from_tree

    arguments = [str(script), flag, json.dumps(spec._asdict())]
    return json_from_tree(src, arguments, show_stderr=show_stderr)


def answer(argv: list[str], commands: dict[str, tuple[type, Callable[[Any], dict]]]) -> bool:
    """The fresh process's side of :func:`in_fresh_process`: ``argv`` is ``FLAG JSON`` for
    one of ``commands`` (``{flag: (spec type, function)}``): the function of the spec, its
    result printed as JSON; True. False when ``argv`` is not such a call."""
    if not argv or argv[0] not in commands:
        return False
    spec_type, function = commands[argv[0]]
    print(json.dumps(function(spec_type(**json.loads(argv[1])))))
    return True


# -- the time to a target -----------------------------------------------------------------------
def first_at_target(history: list[dict], met: Callable[[dict], bool]) -> dict | None:
    """The first evaluation of ``history`` that ``met`` the target, or None."""
    return next((h for h in history if met(h)), None)


def to_target(history: list[dict], met: Callable[[dict], bool]) -> dict:
    """A run's time to its target from its evaluations (each with ``steps``, ``wall``):
    ``reached``, and ``steps`` and ``wall`` of the first evaluation that ``met`` it, else of
    the last one (censored at the run's end; 0 and 0.0 without any evaluation)."""
    hit = first_at_target(history, met)
    end = hit if hit is not None else (history[-1] if history else {"steps": 0, "wall": 0.0})
    return {"reached": hit is not None, "steps": end["steps"], "wall": end["wall"]}


def charged(history: list[dict], start_steps: int, start_wall: float) -> list[dict]:
    """``history`` (evaluations: ``steps``, ``wall`` of the method's own training, ...) with
    its start's env steps and wall time added to each: what the method cost by then."""
    return [{**h, "steps": h["steps"] + start_steps, "wall": h["wall"] + start_wall}
            for h in history]  # fmt: skip


def total_steps(run: dict) -> int:
    """Env steps to the run's end point (its target, else its end): its start's and its own."""
    return run.get("start_steps", 0) + run["steps"]


def total_wall(run: dict) -> float:
    """Wall time to the run's end point: its start's and its own training's."""
    return run.get("start_wall", 0.0) + run["wall"]


def median_or_none(values: list[float]) -> float | None:
    return float(np.median(values)) if values else None


def over_seeds(runs: list[dict]) -> tuple[int, float | None, float | None]:
    """``(seeds that reached the target, median env steps, median wall time)``, the medians
    (start charged) over the seeds that reached it, None where none did."""
    hits = [r for r in runs if r["reached"]]
    return (len(hits), median_or_none([total_steps(r) for r in hits]),
            median_or_none([total_wall(r) for r in hits]))  # fmt: skip


def censored_median_wall(runs: list[dict]) -> tuple[float, bool]:
    """The median wall time to the target over all seeds, a seed that did not reach it
    counted as later than its whole run: ``(seconds, lower bound only)``; when that median
    is such a seed, the median of the runs' ends, a lower bound."""
    mid = float(np.median([total_wall(r) if r["reached"] else math.inf for r in runs]))
    if math.isfinite(mid):
        return mid, False
    return float(np.median([total_wall(r) for r in runs])), True


def split(total: float, start: float, show: Callable[[float], str]) -> str:
    """``total`` as "start + own = **total**" where a start was charged (``show`` writes each)."""
    if not start:
        return show(total)
    return f"{show(start)} + {show(total - start)} = **{show(total)}**"


# -- the start gait's search --------------------------------------------------------------------
def start_gait_file(agent: str, preset: str, values: list[dict]) -> Path | None:
    """The gait file a run starts from (``agent_config.start_gait``: the packaged gait for
    "search", else the path); None for an agent that starts from no gait."""
    from cpg_actor.agents import get_agent_spec

    config = compose(agent, preset, values)
    start = getattr(config.agent_config, "start_gait", "")  # trees before the start gaits
    if not start or not getattr(get_agent_spec(agent), "uses_start_gait", False):
        return None
    if start != "search":
        return Path(start).resolve()
    from cpg_actor.agents.start_gait import packaged_gait_path
    from cpg_actor.robots.registry import get_robot

    robot = get_robot(config.robot)
    return packaged_gait_path(robot.start_gait, robot.name)


def recorded_search(source: Path, budget: int | None, values: list[dict]) -> tuple[dict, dict]:
    """The gait file ``source`` and the search it records, as config values: its ``agent``,
    ``robot``, ``seed``, ``es.episodes`` and ``total_steps`` (``budget``, else the file's
    ``steps_searched``), on the runs' env (the ``env`` values of ``values``)."""
    from cpg_actor.agents.gait_file import load_gait

    gait = load_gait(source)
    search = {
        "agent": gait.get("agent", "open-loop-es"), "robot": gait["robot"],
        "seed": int(gait["seed"]), "es": {"episodes": gait.get("episodes", 1)},
        "total_steps": budget or int(gait.get("steps_searched", gait["steps"])),
    }  # fmt: skip
    physics = env_values(values)
    if physics:
        search["env"] = physics
    return gait, search


def search_result(source: Path, config, runner, path: str | Path, difference: float) -> dict:
    """A search rerun: its gait file, agent, seed and budget, its env steps and wall time
    (generations, evaluations excluded), the gait it found (at ``path``) and how far that is
    from the file's (0.0: the same gait)."""
    return {"source": str(source), "agent": config.agent, "seed": config.seed,
            "budget": config.total_steps, "steps": runner.global_step,
            "wall": runner.train_wall, "gait": str(path), "difference": difference}  # fmt: skip


def gait_difference(found: dict, packaged: dict) -> float:
    """The largest relative difference between two gaits' parameters (0.0: the same gait;
    inf where they do not have the same fields or shapes)."""
    if set(found) != set(packaged):
        return math.inf
    largest = 0.0
    for key in found:
        a, b = np.asarray(found[key], dtype=float), np.asarray(packaged[key], dtype=float)
        if a.shape != b.shape:
            return math.inf
        scale = np.maximum(np.abs(b), 1e-12)
        largest = max(largest, float(np.max(np.abs(a - b) / scale, initial=0.0)))
    return largest


# -- the hopper's physics ceiling and SB3 ----------------------------------------------------------
def hopper_ceiling(num_envs: int, budget: int = 50_000) -> float:
    """``mujoco.rollout``'s control steps per second for ``num_envs`` hoppers, best of 2
    blocks of ``budget`` control steps."""
    sys.path.insert(0, str(HERE))
    from env_throughput import bench_size

    return bench_size("mujoco", num_envs, repeats=2, budget=budget)["rollout"]


class SB3Policy:
    """An SB3 model behind the :class:`cpg_actor.training.policy.Policy` calls
    :func:`evaluate` makes."""

    def __init__(self, model, low: np.ndarray, high: np.ndarray) -> None:
        self.model, self.low, self.high = model, low, high

    def reset(self, num_envs: int) -> None:
        pass

    def act(self, obs: np.ndarray, deterministic: bool = True):
        import torch

        from cpg_actor.training.policy import PolicyStep

        action, _ = self.model.predict(np.asarray(obs), deterministic=True)  # in [-1, 1]
        desired = self.low + (np.asarray(action) + 1.0) * (self.high - self.low) / 2.0
        agent = SimpleNamespace(extras={})
        return PolicyStep(desired.astype(np.float32), torch.as_tensor(obs), torch.zeros(0), agent)


def sb3_history(env, seed: int, budget: int, physics: dict, every: int, episodes: int,
                numbers: Callable[[dict], dict], met: Callable[[dict], bool], stop: bool = True,
                traces: bool = False) -> list[dict]:  # fmt: skip
    """SB3's PPO (``MlpPolicy``, its defaults, on the CPU) on ``env`` (the hopper's, actions
    rescaled to [-1, 1], on the ``physics`` env values) for ``budget`` env steps, evaluated as
    the project's runs (:func:`cpg_actor.training.evaluation.evaluate`: the mean action,
    ``episodes`` episodes on envs of their own, the run's evaluation seed; ``traces`` kept)
    before training, every ``every`` env steps and at the end. Its evaluations as ``{"steps",
    "wall", **numbers(evaluate's result)}``, ``wall`` its training wall time without them; it
    stops at the first that ``met`` the target if ``stop``. ``env`` is closed at the end."""
    import gymnasium as gym
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback

    from cpg_actor.robots.hopper.config import HopperConfig
    from cpg_actor.robots.hopper.plugin import ENV_ID
    from cpg_actor.robots.hopper.vector import HopperVectorEnv
    from cpg_actor.training.evaluation import evaluate
    from cpg_actor.training.seeding import EVAL_SEED_KEY, derived_seed

    eval_config = HopperConfig(**physics)
    eval_env = HopperVectorEnv(episodes, eval_config)
    probe = gym.make(ENV_ID, **physics)
    low, high = probe.unwrapped.action_space.low, probe.unwrapped.action_space.high
    probe.close()
    history: list[dict] = []
    clock = {"start": 0.0, "eval": 0.0, "last": -1}

    class Evaluate(BaseCallback):
        def _on_training_start(self) -> None:
            clock["start"] = time.perf_counter()
            self.evaluate_now()

        def _on_step(self) -> bool:
            if self.num_timesteps - clock["last"] < every:
                return True
            return not (self.evaluate_now() and stop)

        def _on_training_end(self) -> None:
            if clock["last"] != self.num_timesteps:  # the budget's end between evaluations
                self.evaluate_now()

        def evaluate_now(self) -> bool:
            """Evaluate; True if the target is met."""
            begin = time.perf_counter()
            result = evaluate(SB3Policy(self.model, low, high), eval_env,
                              seed=derived_seed(seed, EVAL_SEED_KEY),
                              control_dt=float(eval_config.control_dt),
                              max_steps=eval_config.episode_steps, traces=traces)  # fmt: skip
            measured = numbers(result)
            clock["eval"] += time.perf_counter() - begin
            clock["last"] = self.num_timesteps
            wall = time.perf_counter() - clock["start"] - clock["eval"]
            history.append({"steps": int(self.num_timesteps), "wall": wall, **measured})
            return met(history[-1])

    model = PPO("MlpPolicy", env, seed=seed, device="cpu", verbose=0)
    try:
        model.learn(total_timesteps=budget, callback=Evaluate())
    finally:
        env.close()
        eval_env.close()
    return history
