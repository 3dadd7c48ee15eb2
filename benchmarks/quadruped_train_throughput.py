"""Quadruped PPO training on the CPU next to its two ceilings, paired per iteration in one run,
and where an iteration's time goes.

    python benchmarks/quadruped_train_throughput.py [--case go1/playground/mlp ...]
        [--checkpoint CASE=PATH ...] [--iterations 6] [--num-envs N] [--no-compile]
        [--set KEY=VALUE ...] [--json] [--output benchmarks/results/quadruped_train_throughput.md]

A case is ``ROBOT/PRESET/AGENT[:LABEL]`` (PRESET ``-``: the robot's own recipe; LABEL tells two
cases apart), composed as ``cpg-actor train --robot ROBOT --preset PRESET --agent AGENT``
composes it (``eval_interval=0``); default: the Go1 under MuJoCo Playground's recipe with the
``mlp`` agent and under ``omni`` with the CPG-Actor. One warm-up iteration (and the compiles),
then ``--iterations`` timed ones, each a whole iteration (``Runner.collect`` +
``Runner.update``). ``--checkpoint CASE=PATH`` starts a case from a checkpoint of a run of it
(its agent, normaliser and episodes in progress): a trained policy's walking robots, whose
episodes seldom end, instead of a new run's falling ones.

The physics ceiling, before each timed iteration: ``mujoco.rollout`` of the env's own model
(the same MJCF, actuators, timestep and substeps) stepping the same robots on the same threads
through as many control steps as an iteration has, from the env's current states with the last
desired joint positions held, nothing else: the faster of MuJoCo's own pool and the env's
``ThreadedRollout``, each the best of two. The replayed motion: the env's own physics calls of
the iteration (their start states and controls, recorded) replayed back to back right after it:
the training's motion with nothing between the calls.

The arithmetic ceiling of the update, once per case: the matrix products of the update alone
(every ``nn.Linear`` of the agent: forward, the gradient of its weight, the gradient of its
input where one flows, for every minibatch of every epoch; the forward of the finite check over
the rollout), each ``torch.mm`` of those shapes timed on the update's threads, the best of
five. What the update would take if nothing but its arithmetic ran at this machine's matrix
speed (the CPG's few elementwise operations not counted).

The breakdown: ``time.perf_counter`` around the parts (self time: a part's time less the
timed parts it calls), summed over the timed iterations, per control step of one robot.
Collection: physics (the env's ``mujoco.rollout`` calls, the calling thread's wait for its
helpers included), the task's step split into its reward terms, its observation and the rest of
its bookkeeping (contacts, scaling, episode metrics), the observation noise (the recipe's and a
perturbation's), the command process (resampling within an episode), resets (new episodes'
poses, commands and first observations), randomisation (each new episode's model), the rest of
the env's step (actions, readings, info), the torch face (numpy to tensors), the policy and
CPG (``Policy.act``), storage, the episode log, the rest of recording a step (values of cut
episodes, reward scaling, agent states), the rest of the collection (returns, loop). Update:
the gradient steps (the compiled loss, gradient, clip and Adam), the minibatch gathers, the
finite check, the rest (snapshot, host syncs, statistics). For an agent with a CPG, the CPG
step's share of the update: its forward and backward (the actor given its feedback) against
the whole loss's, both eager, on one minibatch. And where MuJoCo spends a step (its own
timers: constraint solver, collision, ...), the robots as the timed iterations left them.

The machine's speed may drift during a run: every share is paired (measured in the same run,
next to what it is compared with) and ratios of medians over the iterations are reported.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from collections import defaultdict
from pathlib import Path

from cpg_actor.machine import brief_openmp_spinning, cpu_model, load_average, usable_cores

brief_openmp_spinning(os.environ)  # as the cpg-actor command runs (before torch loads)

import numpy as np  # noqa: E402
import torch  # noqa: E402

from bench_report import measured, write  # noqa: E402
from cpg_actor.config import compose_config, parse_override  # noqa: E402
from cpg_actor.ppo.algorithm import ppo_loss  # noqa: E402
from cpg_actor.robots.common.mujoco_runtime import CONTROL_SPEC, mujoco  # noqa: E402
from cpg_actor.robots.common.quadruped import vector as quadruped_vector  # noqa: E402
from cpg_actor.robots.common.threaded_rollout import ThreadedRollout  # noqa: E402
from cpg_actor.tasks import velocity  # noqa: E402
from cpg_actor.training.runner import Runner  # noqa: E402
from cpg_actor.training.threads import update_threads  # noqa: E402

DEFAULT_CASES = ("go1/playground/mlp", "go1/omni/cpg-actor")
# the parts of an iteration, in the table's order, with their headings
COLLECT_PARTS = {
    "physics": "physics",
    "task_reward": "task: reward terms",
    "task_obs": "task: observation",
    "task_rest": "task: rest of its step",
    "noise": "observation noise",
    "command": "command process",
    "resets": "resets",
    "randomise": "randomisation",
    "env_rest": "rest of the env's step",
    "torch_face": "torch face",
    "policy": "policy + CPG",
    "storage": "storage",
    "episode_log": "episode log",
    "record_rest": "rest of recording",
    "collect_rest": "rest of collection",
    "recording": "(this benchmark's record of the physics calls)",
}
UPDATE_PARTS = {
    "gradient_steps": "gradient steps",
    "minibatches": "minibatch gathers",
    "finite_check": "finite check",
    "update_rest": "rest of the update",
}
PARTS = {**COLLECT_PARTS, **UPDATE_PARTS}


class Timer:
    """Self time spent in wrapped callables, by part: a wrapped call's time less that of the
    wrapped calls it makes (the main thread's)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self._children: list[float] = []  # per open call: its timed children's seconds
        self._patched: list[tuple[object, str, object, bool]] = []

    def _close(self, part: str, elapsed: float, children: float) -> None:
        self.seconds[part] += elapsed - children
        if self._children:
            self._children[-1] += elapsed

    def wrap(self, part: str, function):
        def timed(*args, **kwargs):
            self._children.append(0.0)
            start = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                self._close(part, time.perf_counter() - start, self._children.pop())

        return timed

    def wrap_generator(self, part: str, function):
        def timed(*args, **kwargs):
            items = function(*args, **kwargs)
            while True:
                start = time.perf_counter()
                try:
                    item = next(items)
                except StopIteration:
                    self._close(part, time.perf_counter() - start, 0.0)
                    return
                self._close(part, time.perf_counter() - start, 0.0)
                yield item

        return timed

    def patch(self, owner, name: str, part: str, generator: bool = False) -> None:
        """``owner.name`` timed as ``part`` (undone by :meth:`restore`)."""
        original = getattr(owner, name)
        own = name in vars(owner) if hasattr(owner, "__dict__") else True
        self._patched.append((owner, name, original, own))
        wrap = self.wrap_generator if generator else self.wrap
        setattr(owner, name, wrap(part, original))

    def restore(self) -> None:
        for owner, name, original, own in reversed(self._patched):
            if own:
                setattr(owner, name, original)
            else:
                delattr(owner, name)
        self._patched.clear()

    def snapshot(self) -> dict[str, float]:
        return dict(self.seconds)


class TimedCall:
    """A callable object (the fused gradient step) timed as ``part``; its attributes pass."""

    def __init__(self, timer: Timer, part: str, target) -> None:
        self._target = target
        self._call = timer.wrap(part, target)

    def __call__(self, *args, **kwargs):
        return self._call(*args, **kwargs)

    def __getattr__(self, name: str):
        return getattr(self._target, name)


class Ceiling:
    """``mujoco.rollout`` of the env's robots on its threads, nothing else (module doc)."""

    def __init__(self, env, steps: int) -> None:
        self.env, self.steps = env, steps
        model, n, threads = env.model, env.num_envs, env.num_threads
        self.decimation = env.config.decimation
        self.pool = mujoco.rollout.Rollout(nthread=threads if threads > 1 else 0)
        self.datas = [mujoco.MjData(model) for _ in range(threads)]
        self.threaded = ThreadedRollout(model, n, threads)
        self.chunk = max(1, -(-n // (4 * threads)))
        nstate = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS.value)
        self.state = np.zeros((n, nstate))
        self.out = np.zeros((n, self.decimation, nstate))
        self.control = np.zeros((n, self.decimation, model.nu))

    def _start(self) -> None:
        env = self.env
        np.copyto(self.state, env.get_state()[env.quadruped.state_key]["physics"].numpy())
        self.control[:] = env.episode.last_action[:, None, :]

    def _pool_step(self) -> None:
        model = self.env.model
        self.pool.rollout(
            [model] * self.env.num_envs, self.datas, self.state, self.control,
            control_spec=CONTROL_SPEC, skip_checks=True, nstep=self.decimation,
            initial_warmstart=None, state=self.out, chunk_size=self.chunk,
        )  # fmt: skip
        np.copyto(self.state, self.out[:, -1])

    def _threaded_step(self) -> None:
        self.threaded.rollout(self.state, self.control, self.out, None, CONTROL_SPEC,
                              self.decimation)  # fmt: skip
        np.copyto(self.state, self.out[:, -1])

    def rates(self, repeats: int = 2) -> dict[str, float]:
        """Control steps per second (summed over the robots) of MuJoCo's pool and of
        ``ThreadedRollout``, each the best of ``repeats`` runs of an iteration's steps."""
        result = {}
        for name, step in (("pool", self._pool_step), ("threaded", self._threaded_step)):
            best = 0.0
            for _ in range(repeats):
                self._start()
                begin = time.perf_counter()
                for _ in range(self.steps):
                    step()
                best = max(best, self.steps * self.env.num_envs / (time.perf_counter() - begin))
            result[name] = best
        return result

    def replay(self, calls: list[tuple], repeats: int = 2) -> float:
        """Control steps per second of the env's own physics calls of an iteration
        (``calls``: their start states, controls and models, as :class:`Recorder` kept them)
        replayed back to back on a ``ThreadedRollout`` of the env's threads, the sensors read
        as the env reads them; the best of ``repeats``."""
        env = self.env
        next_state = np.zeros_like(env._next)
        sensors = np.zeros_like(env._sensors)
        best = 0.0
        for _ in range(repeats):
            begin = time.perf_counter()
            for state, control, spec, nstep, models in calls:
                self.threaded._models[:] = models  # each robot's (randomised training)
                self.threaded.rollout(state, control, next_state, sensors, spec, nstep)
            seconds = time.perf_counter() - begin
            best = max(best, len(calls) * env.num_envs / seconds)
        self.threaded._models[:] = [env.model] * env.num_envs
        return best

    def close(self) -> None:
        self.pool.close()
        self.threaded.close()


class Recorder:
    """Keeps the start states, controls and models of the env's physics calls
    (:meth:`Ceiling.replay`)."""

    def __init__(self, stepper, timer: Timer) -> None:
        self.calls: list[tuple] = []
        self.on = False
        rollout = stepper.rollout

        def recorded(state, control, next_state, sensordata, spec, nstep):
            if self.on:
                self.calls.append((state.copy(), control.copy(), spec, nstep,
                                   list(stepper._models)))  # fmt: skip
            return rollout(state, control, next_state, sensordata, spec, nstep)

        stepper.rollout = timer.wrap("recording", recorded)


def instrument(runner: Runner, timer: Timer) -> Recorder:
    """Timers around the parts of the run's iteration (module doc)."""
    env = runner.env.unwrapped
    timer.patch(env.stepper, "rollout", "physics")
    recorder = Recorder(env.stepper, timer)  # its copies timed apart from the physics
    for name in ("reward_terms", "field_terms"):
        timer.patch(velocity, name, "task_reward")
    for name in ("observe", "privileged_observation"):
        timer.patch(velocity, name, "task_obs")
    timer.patch(velocity, "step", "task_rest")
    timer.patch(velocity, "resample", "command")
    for name in ("resample_command", "steps_to_next_command"):
        timer.patch(quadruped_vector, name, "command")
    timer.patch(env, "_recipe_noise", "noise")
    timer.patch(env.draws, "observe", "noise")
    start = env._start

    def counted(done):  # the episodes started (ended) per iteration
        timer.seconds["episodes"] += int(np.count_nonzero(done))
        return start(done)

    env._start = counted
    for name in ("_start", "_observe", "_refresh_sensors"):
        timer.patch(env, name, "resets")
    timer.patch(env, "_perturb", "randomise")
    timer.patch(env, "step", "env_rest")
    timer.patch(runner.env, "step", "torch_face")
    rollout = runner.rollout
    timer.patch(rollout.policy, "act", "policy")
    timer.patch(rollout.storage, "add_policy_step", "storage")
    timer.patch(rollout.episodes, "track", "episode_log")
    timer.patch(rollout, "record", "record_rest")
    timer.patch(rollout, "collect", "collect_rest")
    ppo = runner.ppo
    if ppo.fused_step is not None:
        ppo.fused_step = TimedCall(timer, "gradient_steps", ppo.fused_step)
    else:
        timer.patch(ppo, "loss", "gradient_steps")
    timer.patch(runner.storage, "minibatches", "minibatches", generator=True)
    timer.patch(ppo, "_outputs_are_finite", "finite_check")
    timer.patch(ppo, "update", "update_rest")
    return recorder


STAGES = {  # MuJoCo's timers, the parts of a step (mjtTimer)
    "constraint solver": "mjTIMER_CONSTRAINT",
    "collision": "mjTIMER_POS_COLLISION",
    "constraints made": "mjTIMER_POS_MAKE",
    "kinematics and inertia": ("mjTIMER_POS_KINEMATICS", "mjTIMER_POS_INERTIA"),
    "velocity": "mjTIMER_VELOCITY",
    "actuation": "mjTIMER_ACTUATION",
}


def physics_stages(env) -> dict[str, float]:
    """Where MuJoCo spends a control step of the env's robots as they are now (each robot's
    own model and state, its last desired positions, on the calling thread, MuJoCo's timers):
    each stage's share of the step, and the mean contacts, constraint rows and solver
    iterations per substep."""
    seconds = dict.fromkeys(STAGES, 0.0)
    total, contacts, rows, iterations, substeps = 0.0, 0, 0, 0, 0
    state = env.get_state()[env.quadruped.state_key]["physics"].numpy()
    for i in range(env.num_envs):
        model = env.stepper.model_of(i)
        data = mujoco.MjData(model)
        mujoco.mj_setState(model, data, state[i], mujoco.mjtState.mjSTATE_FULLPHYSICS.value)
        data.ctrl[:] = env.episode.last_action[i]
        for _ in range(env.config.decimation):
            mujoco.mj_step(model, data)
            contacts, rows = contacts + data.ncon, rows + data.nefc
            iterations, substeps = iterations + int(data.solver_niter[0]), substeps + 1
        total += data.timer[mujoco.mjtTimer.mjTIMER_STEP].duration
        for stage, timers in STAGES.items():
            for name in (timers,) if isinstance(timers, str) else timers:
                seconds[stage] += data.timer[getattr(mujoco.mjtTimer, name)].duration
    shares = {stage: value / total for stage, value in seconds.items()}
    return {**shares, "contacts": contacts / substeps, "constraint rows": rows / substeps,
            "solver iterations": iterations / substeps}  # fmt: skip


def best_seconds(function, repeats: int = 5, calls: int = 3) -> float:
    """The best of ``repeats`` mean times of ``calls`` calls of ``function``."""
    function()
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(calls):
            function()
        best = min(best, (time.perf_counter() - start) / calls)
    return best


def linear_layers(agent: torch.nn.Module) -> list[tuple[int, int, bool]]:
    """``(in, out, input_gradient)`` of every ``nn.Linear`` of the agent: the first layer of
    an ``nn.Sequential`` reads the observation, which needs no gradient."""
    layers = []
    for module in agent.modules():
        if isinstance(module, torch.nn.Sequential):
            linears = [m for m in module if isinstance(m, torch.nn.Linear)]
            for k, linear in enumerate(linears):
                layers.append((linear.in_features, linear.out_features, k > 0))
    return layers


def update_floor(runner: Runner) -> dict[str, float]:
    """The arithmetic ceiling of the update (module doc): seconds per update of its matrix
    products alone, on the update's threads, and their floating-point operations."""
    cfg = runner.config
    samples = cfg.steps_per_iteration
    minibatch = samples // cfg.ppo.num_minibatches
    steps = cfg.ppo.num_epochs * cfg.ppo.num_minibatches
    torch.set_num_threads(update_threads(cfg))
    cache: dict[tuple[int, int, int], float] = {}

    def mm(rows: int, inner: int, cols: int) -> float:
        key = (rows, inner, cols)
        if key not in cache:
            a, b = torch.randn(rows, inner), torch.randn(inner, cols)
            cache[key] = best_seconds(lambda: torch.mm(a, b))
        return cache[key]

    seconds = flops = 0.0
    try:
        for inputs, outputs, input_gradient in linear_layers(runner.agent):
            # per gradient step: forward, weight gradient, input gradient (if any)
            step = mm(minibatch, inputs, outputs) + mm(outputs, minibatch, inputs)
            step_flops = 4 * minibatch * inputs * outputs
            if input_gradient:
                step += mm(minibatch, outputs, inputs)
                step_flops += 2 * minibatch * inputs * outputs
            seconds += steps * step + mm(samples, inputs, outputs)  # + the finite check
            flops += steps * step_flops + 2 * samples * inputs * outputs
    finally:
        torch.set_num_threads(cfg.torch_threads)
    return {"seconds": seconds, "gflop": flops / 1e9}


def cpg_update_share(runner: Runner) -> float | None:
    """For an agent with a CPG: its step's eager forward and backward (the actor given its
    feedback: the CPG step and the pattern) over the whole eager loss's, on one minibatch of
    the last rollout; None for an agent without one."""
    agent, cfg = runner.agent, runner.config
    if not hasattr(agent, "cpg"):
        return None
    torch.set_num_threads(update_threads(cfg))
    try:
        batch = next(runner.storage.minibatches(cfg.ppo.num_minibatches, cfg.ppo.bptt_steps))

        def whole() -> None:
            agent.zero_grad(set_to_none=True)
            loss, _ = ppo_loss(agent, batch, cfg.ppo)
            loss.backward()

        obs, state = batch["observations"], batch["states"]
        with torch.no_grad():
            feedback = agent.feedback_mean(obs, state)
        feedback.requires_grad_(True)

        def cpg_step() -> None:
            agent.zero_grad(set_to_none=True)
            out = agent.actor(obs, state, feedback)
            (out.mean.sum() + out.next_state.sum()).backward()

        return best_seconds(cpg_step) / best_seconds(whole)
    finally:
        agent.zero_grad(set_to_none=True)
        torch.set_num_threads(cfg.torch_threads)


def parse_case(text: str) -> tuple[str, str | None, str]:
    """``(robot, preset, agent)`` of ``ROBOT/PRESET/AGENT[:LABEL]`` (the label tells apart
    two cases of one run, e.g. one started from a checkpoint)."""
    robot, preset, agent = text.partition(":")[0].split("/")
    return robot, None if preset == "-" else preset, agent


def measure(case: str, args: argparse.Namespace) -> dict:
    robot, preset, agent = parse_case(case)
    values = {"robot": robot, "agent": agent, "eval_interval": 0}
    if args.num_envs is not None:
        values["num_envs"] = args.num_envs
    overrides = list(args.set)
    if args.no_compile:
        overrides.append("ppo.compile=false")
    config = compose_config(preset, None, values, overrides)
    config.total_steps = (args.iterations + 1) * config.steps_per_iteration
    torch.set_num_threads(config.torch_threads)
    runner = Runner(config, run_dir=None, tensorboard=False)
    env = runner.env.unwrapped
    timer = Timer()
    ceiling = Ceiling(env, config.ppo.num_steps)
    rows = []
    try:
        checkpoint = dict(text.split("=", 1) for text in args.checkpoint).get(case)
        if checkpoint is not None:  # a trained state: its agent, normaliser and episodes
            runner.load_checkpoint(Path(checkpoint))
        else:
            runner.start_episodes()
        runner.collect()  # warm-up (and the compiles)
        runner.update()
        floor = update_floor(runner)
        cpg_share = cpg_update_share(runner)
        recorder = instrument(runner, timer)
        for _ in range(args.iterations):
            rates = ceiling.rates()
            recorder.calls.clear()
            recorder.on = True
            before = timer.snapshot()
            start = time.perf_counter()
            runner.collect()
            collected = time.perf_counter()
            runner.update()
            end = time.perf_counter()
            recorder.on = False
            after = timer.snapshot()
            replay = ceiling.replay(recorder.calls)
            spent = {name: after.get(name, 0.0) - before.get(name, 0.0) for name in PARTS}
            ended = after.get("episodes", 0.0) - before.get("episodes", 0.0)
            sps = config.steps_per_iteration / (end - start)
            best = max(rates.values())
            physics_time = config.steps_per_iteration / best
            rows.append({
                "SPS": sps, "ceiling": best, "pool": rates["pool"],
                "threaded": rates["threaded"], "share": sps / best, "replay": replay,
                "share_replay": sps / replay,
                "physics_over_replay": replay * spent["physics"] / config.steps_per_iteration,
                "both_ceilings": config.steps_per_iteration / (physics_time + floor["seconds"]),
                "collect": collected - start, "update": end - collected,
                "update_over_floor": (end - collected) / floor["seconds"],
                "collect_over_physics_ceiling": (collected - start) / physics_time,
                "episodes_ended": ended,
                **{f"t_{k}": v for k, v in spent.items()},
            })  # fmt: skip
            rows[-1]["share_both"] = sps / rows[-1]["both_ceilings"]
        stages = physics_stages(env)
    finally:
        timer.restore()
        ceiling.close()
        runner.close()
    result = {key: statistics.median(row[key] for row in rows) for key in rows[0]}
    samples = args.iterations * config.steps_per_iteration
    total = {name: sum(row[f"t_{name}"] for row in rows) for name in PARTS}
    iteration = sum(row["collect"] + row["update"] for row in rows)
    result["breakdown_us"] = {name: 1e6 * seconds / samples for name, seconds in total.items()}
    ended = sum(row["episodes_ended"] for row in rows)
    result["reset_ms"] = 1e3 * (total["resets"] + total["randomise"]) / max(ended, 1)
    result["iteration_us"] = 1e6 * iteration / samples
    result["untimed_us"] = result["iteration_us"] - sum(result["breakdown_us"].values())
    result.update(
        case=case, num_envs=config.num_envs, threads=env.num_threads,
        steps_per_iteration=config.steps_per_iteration, compile=config.ppo.compile,
        decimation=env.config.decimation, physics_dt=env.config.physics_dt,
        shares=[row["share"] for row in rows], update_floor_s=floor["seconds"],
        update_gflop=floor["gflop"], cpg_update_share=cpg_share,
        bptt_steps=config.ppo.bptt_steps, update_threads=update_threads(config),
        physics_stages=stages,
    )  # fmt: skip
    return result


def table(results: dict[str, dict]) -> list[str]:
    lines = [
        "| case | training SPS | physics ceiling SPS (pool / threaded) | of it, paired (min-max) "
        "| replayed motion SPS | of it | the env's physics over its replay | update floor s "
        "(GFLOP) | update over its floor | both ceilings SPS | of them |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for case, r in results.items():
        lines.append(
            f"| {case} | {r['SPS']:,.0f} | {r['ceiling']:,.0f} ({r['pool']:,.0f} / "
            f"{r['threaded']:,.0f}) | {r['share']:.0%} ({min(r['shares']):.0%}-"
            f"{max(r['shares']):.0%}) | {r['replay']:,.0f} | {r['share_replay']:.0%} | "
            f"{r['physics_over_replay']:.2f} | {r['update_floor_s']:.3f} "
            f"({r['update_gflop']:.1f}) | {r['update_over_floor']:.2f} | "
            f"{r['both_ceilings']:,.0f} | {r['share_both']:.0%} |"
        )
    lines += [
        "",
        "Where an iteration's time goes, us per control step of one robot (self time, summed "
        "over the timed iterations), and its share of the whole iteration:",
        "",
        "| part | " + " | ".join(results) + " |",
        "| --- |" + " ---: |" * len(results),
    ]
    for part, heading in PARTS.items():
        cells = []
        for r in results.values():
            us = r["breakdown_us"][part]
            cells.append(f"{us:.1f} ({us / r['iteration_us']:.1%})")
        lines.append(f"| {heading} | " + " | ".join(cells) + " |")
    lines.append("| untimed (the runner around them) | " + " | ".join(
        f"{r['untimed_us']:.1f} ({r['untimed_us'] / r['iteration_us']:.1%})"
        for r in results.values()) + " |")  # fmt: skip
    lines.append("| **whole iteration** | " + " | ".join(
        f"{r['iteration_us']:.1f}" for r in results.values()) + " |")  # fmt: skip
    lines += ["", "Episodes ended per iteration (median) and the time of a new episode (resets "
              "and randomisation, per episode): " + ", ".join(
                  f"{c} {r['episodes_ended']:.0f}, {r['reset_ms']:.2f} ms"
                  for c, r in results.items()) + "."]  # fmt: skip
    lines += [
        "",
        "Where MuJoCo spends a control step of the robots as they are after the timed "
        "iterations (its own timers, each robot's model and state, one thread; the "
        "stages' shares of the step, then the means per substep):",
        "",
        "| | " + " | ".join(results) + " |",
        "| --- |" + " ---: |" * len(results),
    ]
    for stage in (*STAGES, "contacts", "constraint rows", "solver iterations"):
        cells = []
        for r in results.values():
            value = r["physics_stages"][stage]
            cells.append(f"{value:.0%}" if stage in STAGES else f"{value:.1f}")
        lines.append(f"| {stage} | " + " | ".join(cells) + " |")
    cpg = {case: r["cpg_update_share"] for case, r in results.items()
           if r["cpg_update_share"] is not None}  # fmt: skip
    if cpg:
        lines += ["", "The CPG step's share of the update's loss, forward and backward, eager "
                  "(bptt_steps = " + ", ".join(
                      f"{results[c]['bptt_steps']} for {c}" for c in cpg) + "): " + ", ".join(
                      f"{c} {s:.0%}" for c, s in cpg.items()) + "."]  # fmt: skip
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", nargs="+", default=list(DEFAULT_CASES),
                        help="ROBOT/PRESET/AGENT[:LABEL] (PRESET '-': the robot's recipe; "
                        "LABEL: a name telling two cases apart)")  # fmt: skip
    parser.add_argument("--iterations", type=int, default=6, help="timed iterations per case")
    parser.add_argument("--num-envs", type=int, default=None, help="override the recipe's")
    parser.add_argument("--no-compile", action="store_true", help="ppo.compile=false")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a config override, as cpg-actor train --set")  # fmt: skip
    parser.add_argument(
        "--checkpoint",
        action="append",
        default=[],
        metavar="CASE=PATH",
        help="start CASE from a checkpoint of a run of it (a trained state)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON line, write nothing")
    parser.add_argument("--output", default="benchmarks/results/quadruped_train_throughput.md")
    args = parser.parse_args()
    if args.iterations < 1:
        parser.error(f"--iterations must be >= 1, got {args.iterations}")
    if args.num_envs is not None and args.num_envs < 1:
        parser.error(f"--num-envs must be >= 1, got {args.num_envs}")
    for case in args.case:
        if case.partition(":")[0].count("/") != 2 or args.case.count(case) > 1:
            parser.error(
                f"--case {case!r}: give ROBOT/PRESET/AGENT[:LABEL], each once, e.g. "
                "go1/playground/mlp"
            )
    for text in args.checkpoint:
        case, _, path = text.partition("=")
        if case not in args.case or not Path(path).is_file():
            parser.error(f"--checkpoint {text!r}: give CASE=PATH, a case of --case and a file")
    for text in args.set:
        try:
            parse_override(text)
        except ValueError as error:
            parser.error(str(error))
    results = {}
    for case in args.case:
        results[case] = measure(case, args)
        print(case, json.dumps(results[case]), file=sys.stderr, flush=True)
    if args.json:
        print(json.dumps(results))
        return
    command = (
        f"python benchmarks/quadruped_train_throughput.py --case {' '.join(args.case)} "
        f"--iterations {args.iterations}"
        + (f" --num-envs {args.num_envs}" if args.num_envs else "")
        + (" --no-compile" if args.no_compile else "")
        + "".join(f" --set {text}" for text in args.set)
        + "".join(f" --checkpoint {text}" for text in args.checkpoint)
    )
    lines = [
        "# Quadruped training throughput on the CPU, against its ceilings",
        "",
        measured(command) + f", on {cpu_model()}, {usable_cores()} usable cores "
        f"(load {load_average()}), torch {torch.__version__}, mujoco {mujoco.__version__}.",
        "",
        "Per case (robot/recipe/agent): training SPS of whole iterations (collection and "
        "update); the physics ceiling (`mujoco.rollout` of the env's own model, the same robots "
        "and threads, an iteration's control steps from the env's states, the faster of "
        "MuJoCo's pool and the env's `ThreadedRollout`, right before each timed iteration); the "
        "replayed motion (the iteration's own physics calls back to back); the update's "
        "arithmetic floor (its matrix products alone at this machine's `torch.mm` speed, on "
        "the update's threads); both ceilings together (the physics ceiling's time plus the "
        "update's floor per iteration). Shares are medians over the iterations of each one's "
        "SPS over the ceiling measured beside it (module docstring).",
        "",
        *table(results),
        "",
    ]
    write(args.output, lines)


if __name__ == "__main__":
    main()
