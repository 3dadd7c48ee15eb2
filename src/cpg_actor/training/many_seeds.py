"""Many seeds in one process: K PPO runs, one per seed, over one batched env of K x N envs.

On a GPU the simulator is the cost of a run and grows little with the batch, so K seeds that
step one env of ``K * num_envs`` robots together cost little more than one. Each seed is a
whole run of its own (:class:`~cpg_actor.training.runner.Runner`: its agent, normaliser,
optimiser, rollout storage, evaluation, logs and checkpoints, built from its config with its
seed), acting on its own slice of the env's rows (:class:`SeedSlice`). At each control step
every seed acts on its rows, the env steps once for all of them, and each seed stores its rows
(:meth:`SeedGroup.collect`); then each seed's PPO update runs on its own rollout.

What differs from K separate runs: the env is reset once, with the first seed's episode seed,
so a seed's envs start other episodes than in a run of its own; the seeds draw their action
noise from torch's one generator in turn. The runs are as reproducible (the same seeds in the
same order give the same numbers) but not equal, number for number, to separate runs.
Agents with a warm start before PPO (``mlp-warm``, ``cho2019-warm``) are not supported here.

Checkpoints. Each seed's checkpoint is a run's (its networks, optimiser, normalisers, the
episode statistics, observations and CPG states of its rows, the RNG streams, which are the
group's, the same in every seed's) and names its group (``seed_group``: the seeds, its
index); the first seed's also holds the whole env's state (every seed's rows: the physics,
episode clocks and generators). The group resumed from the checkpoints of one iteration
(:meth:`SeedGroup.resume`, ``cpg-actor train --seeds K --resume``) therefore continues
exactly as the uninterrupted group. One seed resumed alone (``--resume --run-dir
RUN/seed-S``) cannot: its envs were stepped by the group's env and its random numbers drawn
from the group's generator in turn with the other seeds'; it continues as a run of its own,
from new episodes (a group of one seed: from its episodes, as the group would).
"""

from __future__ import annotations

import contextlib
import copy
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import torch

from cpg_actor.agents import get_agent_spec
from cpg_actor.config import TrainConfig
from cpg_actor.device import resolve_device
from cpg_actor.robots.common.torch_env import EnvStep, TorchVectorEnv
from cpg_actor.robots.registry import get_robot
from cpg_actor.training import run_checkpoint
from cpg_actor.training.build import make_env
from cpg_actor.training.evaluation import evaluation_env
from cpg_actor.training.hooks import Checkpoints, Iteration
from cpg_actor.training.runner import Runner
from cpg_actor.training.seeding import derived_seed


def seed_dir(run_dir: Path | str, seed: int) -> Path:
    """Where seed ``seed`` of a group in ``run_dir`` keeps its run (a run directory of its own:
    ``cpg-actor eval``, ``--resume`` alone)."""
    return Path(run_dir) / f"seed-{seed}"


def rows_of(out: EnvStep, rows: slice) -> EnvStep:
    """One seed's rows of a step of the group's env (its ``info`` is the env's, whole)."""
    return EnvStep(
        out.obs[rows], out.reward[rows], out.terminated[rows], out.truncated[rows],
        out.final_obs[rows],
        {name: value[rows] for name, value in out.episode_metrics.items()},
        {name: value[rows] for name, value in out.reward_terms.items()},
        out.info,
    )  # fmt: skip


class SeedSlice:
    """The rows ``rows`` of the group's env, as one seed's run sees its env: the spaces and
    robot of the env, ``num_envs`` rows, the observations of the group's last reset. It is
    stepped only through its group (:meth:`SeedGroup.collect`)."""

    def __init__(self, env: TorchVectorEnv, rows: slice) -> None:
        self.group_env, self.rows = env, rows
        self.num_envs = rows.stop - rows.start
        self.single_observation_space = env.single_observation_space
        self.single_action_space = env.single_action_space
        self.robot = env.robot
        self.reset_obs: torch.Tensor | None = None  # the group's last reset, set by the group

    def reset_tensors(self, seed: Any = None) -> tuple[torch.Tensor, dict]:
        if self.reset_obs is None:
            raise RuntimeError("a seed's slice is reset by its group (SeedGroup.start)")
        return self.reset_obs[self.rows], {}

    def step_tensors(self, actions: torch.Tensor, check_finite: bool = True) -> EnvStep:
        raise RuntimeError("a seed's slice steps with its group (SeedGroup.collect)")

    def close(self) -> None:
        """The group's env is closed by the group."""

    def get_state(self) -> dict[str, Any]:
        """The first seed's slice saves the whole env (every seed's rows, module docstring);
        the others save nothing of it."""
        return {"group_env": self.group_env.get_state()} if self.rows.start == 0 else {}

    def set_state(self, state: dict[str, Any]) -> None:
        """The whole env, from the first seed's checkpoint; nothing from another seed's."""
        if self.rows.start == 0:
            if "group_env" not in state:
                raise ValueError("the first seed's checkpoint holds no state of the group's env")
            self.group_env.set_state(state["group_env"])


class SeedGroup:
    """K runs of ``config`` with ``seeds``, each in ``run_dir/seed-S`` (when ``run_dir`` is
    given), over one env of ``K * config.num_envs`` robots (module docstring). ``progress``:
    the first seed's progress display stands for the group's (all step together)."""

    def __init__(
        self, config: TrainConfig, seeds: Sequence[int], run_dir: Path | None = None,
        tensorboard: bool = False, progress: bool = False, progress_interval: float = 30.0,
    ) -> None:  # fmt: skip
        config.validate()
        seeds = list(seeds)
        if not seeds or len(set(seeds)) != len(seeds):
            raise ValueError(f"a seed group needs distinct seeds, got {seeds}")
        if get_agent_spec(config.agent).warm_start is not None:
            raise ValueError(
                f"agent '{config.agent}' starts with a warm start, which a seed group does not "
                "run; train it one seed per process"
            )
        self.config, self.seeds = config, seeds
        robot = get_robot(config.robot)
        n = config.num_envs
        self.env = TorchVectorEnv(
            make_env(config, robot, n * len(seeds), config.env_threads),
            resolve_device(config.device),
        )
        self.runners: list[Runner] = []
        for k, seed in enumerate(seeds):
            seed_config = copy.deepcopy(config)
            seed_config.seed = seed
            directory = None if run_dir is None else seed_dir(run_dir, seed)
            eval_env = evaluation_env(seed_config, robot) if config.eval_interval > 0 else None
            self.runners.append(Runner(
                seed_config, directory, env=SeedSlice(self.env, slice(k * n, (k + 1) * n)),
                tensorboard=tensorboard, eval_env=eval_env, progress=progress and k == 0,
                progress_interval=progress_interval,
            ))  # fmt: skip
            runner = self.runners[-1]
            runner.seed_group = {"seeds": seeds, "index": k}  # named in its checkpoints
            runner.env.saves_state = self.env.saves_state  # the group's env saves its rows

    def resume(self, checkpoints: Sequence[Path]) -> None:
        """Continue every seed from its checkpoint of one iteration (``checkpoints[k]``, seed
        k's; the module docstring); a ValueError if they are not this group's."""
        if not self.env.saves_state:
            raise ValueError("this env cannot save its episodes; a group resumes only from them")
        iterations = set()
        for k, (runner, path) in enumerate(zip(self.runners, checkpoints, strict=True)):
            group = run_checkpoint.read(path, runner.config.agent).get("seed_group")
            if group != runner.seed_group:
                raise ValueError(
                    f"checkpoint {path} is not seed {self.seeds[k]}'s of this group of seeds "
                    f"{self.seeds} (it names {group or 'no group'})"
                )
            runner.load_checkpoint(path)
            iterations.add(runner.iteration)
        if len(iterations) != 1:
            raise ValueError(f"the seeds' checkpoints are of different iterations "
                             f"{sorted(iterations)}; a group resumes from one")  # fmt: skip

    def start(self) -> None:
        """Reset the group's env (with the first seed's episode seed) and every seed's
        episodes."""
        obs, _ = self.env.reset(seed=derived_seed(self.seeds[0], 0))
        for runner in self.runners:
            runner.env.unwrapped.reset_obs = obs
            runner.start_episodes()

    def collect(self) -> float:
        """One rollout of every seed, the env stepped once per control step for all of them;
        returns the seconds spent in the env."""
        rollouts = [runner.rollout for runner in self.runners]
        for rollout in rollouts:
            rollout.begin()
        simulation = 0.0
        with contextlib.ExitStack() as stances:
            for runner in self.runners:
                stances.enter_context(runner.compile_stance.calls())
            for _ in range(self.config.ppo.num_steps):
                acted = [rollout.act() for rollout in rollouts]
                start = time.perf_counter()
                out = self.env.step(torch.cat([a.action for a in acted]), check_finite=False)
                simulation += time.perf_counter() - start
                for rollout, action, runner in zip(rollouts, acted, self.runners, strict=True):
                    rollout.record(action, rows_of(out, runner.env.unwrapped.rows))
        return simulation

    def train_iteration(self) -> list[Iteration]:
        """One rollout of every seed, then each seed's PPO update."""
        start = time.perf_counter()
        for runner in self.runners:
            runner.ppo.schedule(runner.iteration, runner.config.num_iterations)
        simulation = self.collect()
        finished = []
        for runner in self.runners:
            with runner.compile_stance.calls():
                finished.append(runner.rollout.finish())
        collect_time = time.perf_counter() - start
        return [
            runner.learn_from({**done, "simulation_time": simulation}, collect_time)
            for runner, done in zip(self.runners, finished, strict=True)
        ]

    def learn(self) -> None:
        """Train every seed to ``config.total_steps``, each run's hooks called as in
        :meth:`Runner.learn` (evaluation, logs, progress, a checkpoint at the end)."""
        for runner in self.runners:
            if runner.run_dir is not None:
                runner.run_dir.mkdir(parents=True, exist_ok=True)
        fresh = not self.runners[0].rollout.started  # not resumed (:meth:`resume`)
        if fresh:
            self.start()
        hooks = [[*runner.hooks, Checkpoints()] for runner in self.runners]
        try:
            for runner, own in zip(self.runners, hooks, strict=True):
                for hook in own:
                    hook.start(runner, fresh)
            while self.runners[0].iteration < self.config.num_iterations:
                iterations = self.train_iteration()
                for runner, own, it in zip(self.runners, hooks, iterations, strict=True):
                    for hook in own:
                        hook.iteration(runner, it)
        finally:
            for runner, own in zip(self.runners, hooks, strict=True):
                for hook in own:
                    hook.end(runner)

    def close(self) -> None:
        for runner in self.runners:
            runner.close()
        self.env.close()
