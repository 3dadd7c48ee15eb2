"""The open-loop search baseline (agent ``open-loop-es``): the open-loop CPG-Actor's vector V
tuned by CMA-ES on the env's return, with no gradient and no feedback.

What is searched: V itself (:attr:`cpg_actor.cpg.parametrisation.Parametrisation.vector`,
paper eq. 3), in V's own coordinates, so whatever transform the parametrisation applies
(exp for nu, rho and a, a bounded map, ties) keeps every candidate a valid CPG. The search
starts at the robot's CPG preset (with ``agent_config.cpg_initial``) and a step size
``es.sigma0`` in V units.

Fitness: each candidate drives ``es.episodes`` full episodes with the CPG's output as the
desired joint positions (the mean action, no noise); its fitness is the mean undiscounted
episode return (eq. 4's reward as the env pays it). Every candidate of a generation meets the
same ``es.episodes`` reset seeds (common random numbers, derived from the run seed and the
generation), so they are ranked on the same starts. The ``popsize x episodes`` episodes of a
generation run in one vector env of as many sub-envs, every candidate's CPG stepped in one
batched call (``torch.func.vmap`` over V of the agent's own control step).

Budget: every env step the search takes counts toward ``total_steps``: a generation costs
``sub-envs x control steps`` until its last episode ended (``popsize x episodes x
episode_steps`` when one runs to the time limit, the hopper's case). A run makes ``total_steps //
(popsize x episodes x episode_steps)`` generations, so it never exceeds ``total_steps``.

CMA-ES (Hansen and Ostermeier 2001, with the defaults of Hansen's ``cma`` package, which runs
it here) minimises ``-fitness``; its random numbers come from a generator of its own
(:class:`NormalSource`, seeded from the run seed), kept with the rest of its state, so a
search continued from a saved state draws exactly what the uninterrupted one would.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
import torch
from torch import Tensor, nn

from cpg_actor.agents.cma_state import restore_search_state, search_state
from cpg_actor.limits import MAX_ENVS, MAX_EPISODES, MAX_POPSIZE, brief, check_int

ES_EPISODE_SEED_KEY = 2**31 + 2  # SeedSequence([seed, this, generation]): reset seeds
ES_SEARCH_SEED_KEY = 2**31 + 3  # SeedSequence([seed, this]): CMA-ES's normal draws


@dataclass
class ESConfig:
    """The open-loop CMA-ES search (agent ``open-loop-es``; other agents ignore it)."""

    # CMA-ES's initial step size, in units of V: log units for nu, rho and a (0.2: about 20 %
    # either way), rad for phase biases, plain units for coupling weights
    sigma0: float = 0.2
    # candidates per generation (CMA-ES's lambda); each runs its episodes in envs of its own
    popsize: int = 16
    # episodes per candidate; its fitness is their mean undiscounted return
    episodes: int = 1

    def validate(self) -> None:
        """ValueError with one line per bad value."""
        problems = []
        sigma0 = self.sigma0
        if (
            isinstance(sigma0, bool)
            or not isinstance(sigma0, (int, float))
            or not (math.isfinite(sigma0) and sigma0 > 0)
        ):
            problems.append(
                f"es.sigma0 must be a finite number > 0 (in V units), got {brief(sigma0)}"
            )
        for name, least, high in (("popsize", 2, MAX_POPSIZE), ("episodes", 1, MAX_EPISODES)):
            try:
                check_int(getattr(self, name), f"es.{name}", least, high)
            except ValueError as error:
                problems.append(str(error))
        if not problems and self.popsize * self.episodes > MAX_ENVS:  # an env each
            problems.append(
                f"es.popsize x es.episodes ({self.popsize:,} x {self.episodes:,}) envs are "
                f"above the {MAX_ENVS:,} accepted"
            )
        if problems:
            raise ValueError("\n".join(problems))


# -- the budget -----------------------------------------------------------------------------
def generation_steps(config: Any) -> int:
    """The most env steps one generation can take: ``popsize x episodes x episode_steps``."""
    return config.es.popsize * config.es.episodes * config.env.episode_steps


def num_generations(config: Any) -> int:
    """The generations a run of ``config.total_steps`` makes (module docstring, Budget);
    ValueError if not even one fits."""
    per_generation = generation_steps(config)
    count = config.total_steps // per_generation
    if count < 1:
        raise ValueError(
            f"total_steps {config.total_steps:,} is less than one generation of the open-loop "
            f"search: es.popsize {config.es.popsize} x es.episodes {config.es.episodes} x "
            f"env.episode_steps {config.env.episode_steps} = {per_generation:,} steps"
        )
    return count


def episode_seeds(seed: int, generation: int, episodes: int) -> list[int]:
    """The reset seeds of generation ``generation`` (0-based), one per episode, shared by
    every candidate of the generation."""
    state = np.random.SeedSequence([seed, ES_EPISODE_SEED_KEY, generation]).generate_state(episodes)
    return [int(s) for s in state]


# -- CMA-ES -----------------------------------------------------------------------------------
class NormalSource:
    """Standard normal draws for CMA-ES (its ``randn`` option, called ``randn(*shape)`` as
    ``np.random.randn``) from a generator of its own: the global numpy generator is left
    alone, and its state is saved with the search's (:mod:`.cma_state`)."""

    def __init__(self, seed: int) -> None:
        self.generator = np.random.RandomState(seed)

    def __call__(self, *shape: int) -> np.ndarray:
        return self.generator.standard_normal(shape)


class CMASearch:
    """CMA-ES maximising a fitness over V (``cma.CMAEvolutionStrategy``, which minimises: it
    is told ``-fitness``), and the best candidate evaluated so far.

    ``ask() -> X (popsize, M)``, evaluate, ``tell(X, fitness)``. Non-finite fitness values
    (a simulation blow-up) rank below every finite one. The search ends early when CMA-ES
    reports that it has converged (:attr:`stop_reason`); the generation and evaluation limits
    of ``cma`` are lifted, the budget is the caller's.
    """

    def __init__(self, x0: np.ndarray, sigma0: float, popsize: int, seed: int) -> None:
        self._start = (np.array(x0, dtype=np.float64), float(sigma0), int(popsize), int(seed))
        self.es = self._new_search()
        self.generation = 0
        self.best_fitness = -math.inf
        self.best_x: np.ndarray | None = None
        self.best_generation = 0  # 1-based: the generation that evaluated best_x (0: none)

    def _new_search(self) -> Any:
        """A search at the start, built by cma's constructor from this run's options."""
        import cma

        x0, sigma0, popsize, seed = self._start
        options = {
            "popsize": popsize,
            "randn": NormalSource(seed),
            "seed": float("nan"),  # cma must not seed (or draw from) numpy's global generator
            "maxiter": math.inf,
            "maxfevals": math.inf,
            "verbose": -9,
            "verb_disp": 0,
            "verb_log": 0,
            "signals_filename": "",  # no option changes read from a file in the working dir
        }
        return cma.CMAEvolutionStrategy(x0.copy(), sigma0, options)

    @property
    def sigma(self) -> float:
        return float(self.es.sigma)

    @property
    def mean(self) -> np.ndarray:
        """The search distribution's mean."""
        return np.array(self.es.mean, dtype=np.float64)

    @property
    def stop_reason(self) -> str:
        """Why CMA-ES stopped (its termination criteria), empty while it goes on."""
        if self.generation == 0:
            return ""
        stop = self.es.stop()
        return ", ".join(f"{key}={value}" for key, value in stop.items())

    def ask(self) -> np.ndarray:
        return np.stack(self.es.ask())

    def tell(self, candidates: np.ndarray, fitness: np.ndarray) -> None:
        fitness = np.asarray(fitness, dtype=np.float64)
        finite = np.isfinite(fitness)
        ranked = fitness.copy()
        if not finite.all():  # below every finite value
            floor = fitness[finite].min() if finite.any() else 0.0
            ranked[~finite] = floor - 1.0 - abs(floor)
        self.es.tell(list(candidates), (-ranked).tolist())
        self.generation += 1
        best = int(np.argmax(ranked))
        if finite[best] and fitness[best] > self.best_fitness:
            self.best_fitness = float(fitness[best])
            self.best_x = np.array(candidates[best], dtype=np.float64)
            self.best_generation = self.generation

    # -- state -------------------------------------------------------------------------------
    def state_dict(self) -> dict[str, Any]:
        """Tensors and plain numbers (``torch.load(weights_only=True)`` reads them): CMA-ES's
        state as :func:`~.cma_state.search_state` reads it, the best candidate and the
        counters. No pickle: a checkpoint is numbers only."""
        return {
            "cma": search_state(self.es),
            "generation": self.generation,
            "best_fitness": self.best_fitness,
            "best_x": None if self.best_x is None else torch.from_numpy(self.best_x.copy()),
            "best_generation": self.best_generation,
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Continue from ``state``: a search built anew from this run's options, its numbers
        set from ``state``; ValueError (one line) if ``state`` is not a state of this search."""
        if not isinstance(state, dict):
            raise ValueError(f"the saved search state is a {type(state).__name__}, not a dict")
        saved = state.get("cma")
        if isinstance(saved, torch.Tensor):
            raise ValueError(
                "the saved CMA-ES state is a pickle (an older cpg-actor's checkpoint), which is "
                "not read: it could run code; train the run again"
            )
        if isinstance(saved, dict) and "mean" in saved:
            saved_n = saved["mean"].numel() if isinstance(saved["mean"], torch.Tensor) else None
            if saved_n is not None and saved_n != len(self.es.mean):
                raise ValueError(
                    f"the saved CMA-ES state searches {saved_n} parameters, this agent's V "
                    f"has {len(self.es.mean)}"
                )
        best = state.get("best_x")
        numbers = [state.get(key) for key in ("generation", "best_fitness", "best_generation")]
        if (
            type(numbers[0]) is not int or type(numbers[2]) is not int
            or type(numbers[1]) is not float
            or not (best is None or isinstance(best, torch.Tensor) and best.dtype == torch.float64
                    and tuple(best.shape) == (len(self.es.mean),))
        ):  # fmt: skip
            raise ValueError(
                "the saved search's counters must be integers generation and best_generation, a "
                "float best_fitness and best_x None or a float64 vector of V's size"
            )
        es = self._new_search()
        restore_search_state(es, saved)
        self.es = es
        self.generation, self.best_fitness, self.best_generation = numbers
        self.best_x = None if best is None else best.numpy().copy()


# -- evaluating candidates ---------------------------------------------------------------------
class Rollouts(NamedTuple):
    """The episodes of one generation, ``(popsize, episodes)`` each."""

    returns: np.ndarray  # undiscounted episode returns, float64
    lengths: np.ndarray  # control steps of each episode
    metrics: dict[str, np.ndarray]  # the env's episode metrics (hop_height), NaN if none
    reward_terms: dict[str, np.ndarray]  # each reward term summed over the episode
    env_steps: int  # every env step taken: sub-envs x control steps

    @property
    def fitness(self) -> np.ndarray:
        """Per candidate: the mean return of its episodes."""
        return self.returns.mean(axis=1)


class _ControlStep(nn.Module):
    """The agent's deterministic control step without clipping: ``(obs, state) -> (mean
    action, next state)``, as :class:`cpg_actor.training.policy.Policy` takes it (the open-loop CPG
    ignores the observation but for the drive, which :meth:`observe` reads raw)."""

    def __init__(self, agent: nn.Module) -> None:
        super().__init__()
        self.agent = agent

    def forward(self, obs: Tensor, state: Tensor) -> tuple[Tensor, Tensor]:
        state = self.agent.observe(obs, state)
        out = self.agent.actor(obs, state)
        return out.mean, out.next_state


class CandidateRollouts:
    """Runs ``popsize`` candidate vectors V for ``episodes`` episodes each, all at once, on a
    vector env of ``popsize x episodes`` sub-envs (candidate-major: sub-env ``c * episodes +
    e`` is candidate c's episode e).

    ``agent`` is an open-loop :class:`cpg_actor.agents.CPGActorAgent`; its own control step
    runs under ``torch.func.vmap`` over V (with ``functional_call``), so each candidate
    acts exactly as the agent would with that V. ``env`` is a
    :class:`cpg_actor.robots.common.torch_env.TorchVectorEnv`. Episodes end at the env's
    termination or truncation, or after ``max_steps`` control steps.
    """

    def __init__(self, agent: nn.Module, env: Any, episodes: int, max_steps: int) -> None:
        self.agent = agent
        self.env = env
        self.episodes = episodes
        self.max_steps = max_steps
        step = _ControlStep(agent)
        vector = agent.cpg.parametrisation.vector
        (name,) = [key for key, value in step.named_parameters() if value is vector]

        def one(v: Tensor, obs: Tensor, state: Tensor) -> tuple[Tensor, Tensor]:
            return torch.func.functional_call(step, {name: v}, (obs, state))

        self._step = torch.func.vmap(one)
        space = env.single_action_space
        device = vector.device
        self.low = torch.as_tensor(np.asarray(space.low, dtype=np.float32), device=device)
        self.high = torch.as_tensor(np.asarray(space.high, dtype=np.float32), device=device)

    @torch.no_grad()
    def run(self, vectors: Tensor, seeds: list[int]) -> Rollouts:
        """``vectors`` ``(popsize, M)`` (V's dtype and device); ``seeds``: one reset seed per
        episode index, shared by every candidate."""
        popsize, episodes = vectors.shape[0], self.episodes
        count = popsize * episodes
        if count != self.env.num_envs or len(seeds) != episodes:
            raise ValueError(
                f"{popsize} candidates x {episodes} episodes need {count} envs and {episodes} "
                f"seeds; the env has {self.env.num_envs}, got {len(seeds)} seeds"
            )
        obs, _ = self.env.reset(seed=[int(s) for _ in range(popsize) for s in seeds])
        state = self.agent.initial_state(count)
        shape = tuple(state.shape[1:])
        device = obs.device
        returns = torch.zeros(count, dtype=torch.float64, device=device)
        lengths = torch.zeros(count, dtype=torch.int64, device=device)
        active = torch.ones(count, dtype=torch.bool, device=device)
        metrics: dict[str, Tensor] = {}
        terms: dict[str, Tensor] = {}
        steps = 0
        for _ in range(self.max_steps):
            grouped = (obs.reshape(popsize, episodes, -1), state.reshape(popsize, episodes, *shape))
            mean, state = self._step(vectors, *grouped)
            mean, state = mean.reshape(count, -1), state.reshape(count, *shape)
            action = torch.minimum(torch.maximum(mean, self.low), self.high)
            out = self.env.step(action)
            steps += 1
            reward = out.reward.to(torch.float64)
            returns += torch.where(active, reward, torch.zeros_like(reward))
            lengths += active.to(torch.int64)
            for key, value in out.reward_terms.items():
                total = terms.setdefault(key, torch.zeros_like(returns))
                total += torch.where(active, value.to(torch.float64), torch.zeros_like(total))
            ended = active & (out.terminated | out.truncated)
            for key, value in out.episode_metrics.items():
                metric = metrics.setdefault(key, torch.full_like(returns, math.nan))
                metric[ended] = value.to(torch.float64)[ended]
            active &= ~ended
            obs = out.obs
            if not bool(active.any()):
                break

        def table(values: Tensor) -> np.ndarray:
            return values.cpu().numpy().reshape(popsize, episodes)

        return Rollouts(
            returns=table(returns),
            lengths=table(lengths),
            metrics={key: table(value) for key, value in metrics.items()},
            reward_terms={key: table(value) for key, value in terms.items()},
            env_steps=steps * count,
        )
