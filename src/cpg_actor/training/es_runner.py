"""The training loop of the open-loop search baseline (agent ``open-loop-es``): CMA-ES
generations instead of PPO iterations, with the run directory of any other run.

One generation (:mod:`cpg_actor.agents.open_loop_es`): CMA-ES proposes ``es.popsize``
vectors V, each drives ``es.episodes`` deterministic episodes, and their mean returns update
the search. The agent kept (checkpoints, ``cpg-actor eval``, ``export``, ``load_policy``) is
the open-loop :class:`cpg_actor.agents.CPGActorAgent` with V = the **best candidate evaluated
so far**: its fitness is a measured return (on the episodes it was selected on, a slightly
optimistic estimate; ``eval/return``, on seeds of its own, is the unbiased one), and the gait
file reports it. The distribution's mean is in the CMA-ES state.

Written in the run directory as a PPO run writes it: ``metrics.jsonl`` and TensorBoard rows per
generation (``es/best_return``, ``es/mean_return``, ``es/sigma``, the population's episode
statistics as ``charts/*`` and ``reward_terms/*``, the CPG's physical parameters ``cpg/*``),
the deterministic evaluation every ``eval_interval`` generations (and before the first and
after the last; :func:`cpg_actor.training.evaluation.evaluate` on envs of its own, seeded as the PPO
runner's, changing nothing that is searched), atomic checkpoints every
``checkpoint_interval`` generations and at the end, and ``gait.yaml``
(:mod:`cpg_actor.agents.gait_file`) with each checkpoint once a generation has run.

Resume: a checkpoint holds the agent, the CMA-ES state (with its random generator), the best
candidate, the counters and the global RNG streams. Every generation resets its envs from
seeds derived from the run seed and the generation, so no episode is in progress between
generations, and a resumed run equals the uninterrupted one bit for bit (MuJoCo).
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch

from cpg_actor.agents import CPGActorAgent, get_agent_spec
from cpg_actor.agents.gait_file import GAIT_FILE, gait_parameters, write_gait
from cpg_actor.agents.open_loop_es import (
    ES_SEARCH_SEED_KEY,
    CandidateRollouts,
    CMASearch,
    Rollouts,
    episode_seeds,
    generation_steps,
    num_generations,
)
from cpg_actor.config import TrainConfig
from cpg_actor.device import resolve_device
from cpg_actor.ppo import RunningNormalizer
from cpg_actor.robots.common.torch_env import TorchVectorEnv
from cpg_actor.robots.registry import get_robot
from cpg_actor.training import run_checkpoint
from cpg_actor.training.build import make_env
from cpg_actor.training.evaluation import TrainingEvaluation, finite_mean
from cpg_actor.training.hooks import Checkpoints, Hook, Iteration, loop_hooks, run_loop
from cpg_actor.training.run_log import RunLog
from cpg_actor.training.seeding import seed_everything


def search_seed(seed: int) -> int:
    """The seed of CMA-ES's own normal draws in a run seeded ``seed``."""
    return int(np.random.SeedSequence([seed, ES_SEARCH_SEED_KEY]).generate_state(1)[0])


class ESRunner:
    """Builds the open-loop agent, the search envs and CMA-ES from a :class:`TrainConfig`
    whose agent trains by search (``AgentSpec.trainer == "es"``), and searches.

    The same face as :class:`cpg_actor.training.runner.Runner` for ``cpg-actor train``: ``learn``,
    ``load_checkpoint``, ``close``, ``iteration`` (generations done), ``global_step``,
    ``train_wall``, ``last_checkpoint_path``. ``env`` and ``eval_env`` replace the agent
    spec's environments (tests).
    """

    def __init__(
        self,
        config: TrainConfig,
        run_dir: Path | None = None,
        env: Any = None,
        progress: bool = False,
        tensorboard: bool = True,
        eval_env: Any = None,
        progress_interval: float = 30.0,
    ) -> None:
        config.validate()
        self.spec = get_agent_spec(config.agent)
        if self.spec.trainer != "es":
            raise ValueError(
                f"agent '{config.agent}' is trained by {self.spec.trainer}, not by the "
                "open-loop search; use cpg_actor.training.runner.Runner"
            )
        self.config = config
        self.run_dir = Path(run_dir) if run_dir is not None else None
        self.run_log = RunLog(self.run_dir, tensorboard)
        torch.set_num_threads(config.torch_threads)
        self.device = resolve_device(config.device)
        seed_everything(config.seed)
        es = config.es
        self.num_generations = num_generations(config)
        self.generation_steps = generation_steps(config)
        num_envs = es.popsize * es.episodes
        self.robot = get_robot(config.robot)  # the run's robot, resolved once
        if env is None:
            env = make_env(config, self.robot, num_envs, config.env_threads)
        self.env = TorchVectorEnv(env, self.device)
        if self.env.num_envs != num_envs:
            raise ValueError(
                f"the env has {self.env.num_envs} sub-envs; the search needs es.popsize x "
                f"es.episodes = {num_envs}"
            )
        action_space = self.env.single_action_space
        self.action_low = np.asarray(action_space.low, dtype=np.float32)
        self.action_high = np.asarray(action_space.high, dtype=np.float32)
        self.agent = self.spec.build(config.agent_config, self.env, self.robot)
        if not isinstance(self.agent, CPGActorAgent) or self.agent.feedback is not None:
            raise ValueError(
                f"agent '{config.agent}' must build an open-loop CPGActorAgent (feedback=False) "
                "for the search"
            )
        self.agent.to(self.device)
        self.agent.requires_grad_(False)
        # the open-loop CPG ignores observations; an untouched normaliser goes into the
        # checkpoint for load_policy, which expects one
        obs_dim = int(self.env.single_observation_space.shape[0])
        self.normalizer = RunningNormalizer(obs_dim).to(self.device)
        self.vector = self.agent.cpg.parametrisation.vector
        self.start_vector = self.vector.detach().clone()
        self.rollouts = CandidateRollouts(
            self.agent, self.env, es.episodes, config.env.episode_steps
        )
        self.search = CMASearch(
            self.start_vector.double().cpu().numpy(),
            es.sigma0,
            es.popsize,
            search_seed(config.seed),
        )
        self.evaluation = TrainingEvaluation(
            config, self.robot, self.agent, self.normalizer, self.action_low, self.action_high,
            eval_env,
        )  # fmt: skip
        self.hooks: list[Hook] = loop_hooks(
            self.evaluation, ESRunner.scalars, ESRunner.progress_fields, progress, progress_interval
        )
        self.iteration = 0  # generations done
        self.global_step = 0  # env steps the search took
        self.best_step = 0  # global_step when the best candidate was found
        self.train_wall = 0.0  # seconds of search (rollouts + CMA-ES), over the whole run
        self.last_evaluation: dict[str, float] | None = None
        self.last_row: dict[str, float] = {}
        self._resumed = False

    # -- the search --------------------------------------------------------------------------
    @property
    def stop_reason(self) -> str:
        """Why CMA-ES stopped before the budget (empty while it goes on)."""
        return self.search.stop_reason

    @property
    def finished(self) -> bool:
        return self.iteration >= self.num_generations or bool(self.stop_reason)

    @property
    def planned_steps(self) -> int:
        return self.num_generations * self.generation_steps

    def evaluate_candidates(self, candidates: np.ndarray) -> Rollouts:
        """The episodes of this generation's candidates ``(popsize, M)``, from its seeds."""
        vectors = torch.as_tensor(candidates, dtype=self.vector.dtype, device=self.device)
        seeds = episode_seeds(self.config.seed, self.iteration, self.config.es.episodes)
        return self.rollouts.run(vectors, seeds)

    def generation(self) -> tuple[Rollouts, np.ndarray]:
        """Ask, evaluate, tell; the agent takes the best candidate so far. Returns the
        generation's episodes and fitness."""
        candidates = self.search.ask()
        rollouts = self.evaluate_candidates(candidates)
        fitness = rollouts.fitness
        self.search.tell(candidates, fitness)
        self.iteration += 1
        self.global_step += rollouts.env_steps
        if self.search.best_generation == self.iteration:  # a new best
            self.best_step = self.global_step
            with torch.no_grad():
                self.vector.copy_(torch.as_tensor(self.search.best_x, dtype=self.vector.dtype))
        return rollouts, fitness

    def learn(self) -> None:
        """Search to the budget (``num_generations``) or until CMA-ES stops, calling the
        hooks (:mod:`cpg_actor.training.hooks`)."""
        if self.run_dir is not None:
            self.run_dir.mkdir(parents=True, exist_ok=True)
        fresh = self.iteration == 0 and not self._resumed
        run_loop(self, [*self.hooks, Checkpoints()], fresh, lambda: not self.finished)

    def train_iteration(self) -> Iteration:
        """One generation, timed; its episodes and fitness go to the rows."""
        start = time.perf_counter()
        rollouts, fitness = self.generation()
        seconds = time.perf_counter() - start
        self.train_wall += seconds
        sps = rollouts.env_steps / seconds if seconds > 0 else math.nan
        timing = {"SPS": sps, "generation": seconds}
        extras = {"rollouts": rollouts, "fitness": fitness}
        return Iteration(self.iteration, self.finished, {}, timing, extras=extras)

    # -- logging -----------------------------------------------------------------------------
    def scalars(self, it: Iteration) -> dict[str, float]:
        """One generation's row: the search, the population's episodes, the CPG kept."""
        rollouts, fitness = it.extras["rollouts"], it.extras["fitness"]
        row = {
            "es/best_return": self.search.best_fitness,
            "es/generation_best_return": float(np.max(fitness)),
            "es/mean_return": float(np.mean(fitness)),
            "es/sigma": self.search.sigma,
            "es/best_generation": float(self.search.best_generation),
            "charts/episode_return": float(rollouts.returns.mean()),
            "charts/episode_length": float(rollouts.lengths.mean()),
        }
        for name, values in sorted(rollouts.metrics.items()):  # the env's own (hop_height)
            row[f"charts/{name}"] = finite_mean(values)
        for name, values in sorted(rollouts.reward_terms.items()):
            row[f"reward_terms/{name}"] = float(values.mean())
        row["charts/SPS"] = it.timing["SPS"]
        row["time/generation"] = it.timing["generation"]
        row["time/train_wall"] = self.train_wall
        # the CPG's physical parameters; not the Gaussian's std, which the search never uses
        row.update(
            {k: v for k, v in self.agent.log_scalars().items() if not k.startswith("policy/")}
        )
        return row

    def run_evaluation(self) -> dict[str, float]:
        """Deterministic episodes of the kept agent on the evaluation envs, seeded as the PPO
        runner's (:class:`cpg_actor.training.evaluation.TrainingEvaluation`)."""
        return self.evaluation()

    def progress_fields(self, it: Iteration) -> dict[str, str]:
        """The progress display's fields of a generation."""
        fitness = it.extras["fitness"]
        return {
            "sps": f"{it.timing['SPS']:,.0f}",
            "ret": f"best {self.search.best_fitness:.2f} mean {fitness.mean():.2f}",
            "metrics": f"generation {self.iteration}/{self.num_generations} "
            f"sigma {self.search.sigma:.3g}",
        }

    # -- checkpoints and the gait file -------------------------------------------------------
    def last_checkpoint_path(self) -> Path | None:
        return run_checkpoint.last_path(self.run_dir)

    def gait_path(self) -> Path | None:
        return None if self.run_dir is None else self.run_dir / GAIT_FILE

    def state_dict(self) -> dict[str, Any]:
        return {
            **run_checkpoint.run_state(self),
            "es": {
                **self.search.state_dict(),
                "best_step": self.best_step,
                "start_vector": self.start_vector.cpu().clone(),
            },
        }

    def save_checkpoint(self) -> Path:
        """``checkpoints/iter_<generation>.pt`` and ``last.pt``, then ``gait.yaml`` (once a
        candidate has been evaluated)."""
        assert self.run_dir is not None
        path = run_checkpoint.save(self.state_dict(), self.run_dir, self.iteration)
        self.write_gait()
        return path

    def gait(self) -> dict[str, Any] | None:
        """The gait file's content (:mod:`cpg_actor.agents.gait_file`) for the best candidate
        so far; None before the first generation."""
        if self.search.best_x is None:
            return None
        cfg = self.config
        return {
            "robot": cfg.robot,
            "agent": cfg.agent,
            "cpg_layout": self.agent.layout,
            "cpg_gait": cfg.agent_config.cpg_gait,
            "fitness": self.search.best_fitness,
            "episodes": cfg.es.episodes,
            "steps": self.best_step,
            "generation": self.search.best_generation,
            "steps_searched": self.global_step,
            "seed": cfg.seed,
            "cpg_initial": gait_parameters(self.agent),
        }

    def write_gait(self) -> Path | None:
        gait = self.gait()
        path = self.gait_path()
        if gait is None or path is None:
            return None
        return write_gait(path, gait)

    def load_checkpoint(self, path: Path) -> None:
        """Continue the search from ``path`` (the agent, CMA-ES, the best candidate, counters,
        RNG streams). To act with the agent, see :func:`cpg_actor.deploy.load_policy`."""
        data = run_checkpoint.read(path, self.config.agent)
        state = data.get("es")
        if not isinstance(state, dict):
            raise ValueError(f"checkpoint {path} holds no search state")
        start, best_step = state.get("start_vector"), state.get("best_step")
        if type(best_step) is not int or not (
            isinstance(start, torch.Tensor) and start.shape == self.start_vector.shape
        ):
            raise ValueError(
                f"checkpoint {path}: its search state needs an integer best_step and a "
                f"start_vector of V's {self.start_vector.numel()} values"
            )
        run_checkpoint.restore_run_state(self, path, data)
        self.search.load_state_dict(state)
        self.best_step = best_step
        self.start_vector = start.to(self.device, self.start_vector.dtype).clone()
        self._resumed = True

    def close(self) -> None:
        self.run_log.close()
        self.env.close()
        for hook in self.hooks:
            hook.close()
