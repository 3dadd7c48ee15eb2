"""The training loop: rollouts with the CPG state carried per environment, PPO updates,
logging (console, TensorBoard, metrics.jsonl) and atomic, resumable checkpoints.

Evaluation during training. Every ``eval_interval`` iterations (and before the first and
after the last) the policy's mean action runs one episode on each of ``eval_episodes``
environments of its own, always reset with the same seed (:mod:`cpg_actor.evaluation`); the
mean return and the env's episode metrics are logged as ``eval/return`` and ``eval/<metric>``
(the hopper's ``eval/hop_height``). It draws no random numbers and touches neither the
training envs nor the normaliser, so a run trains the same with or without it.
``time/train_wall`` is the run's wall time without evaluation and checkpoints (what
``benchmarks/time_to_hop.py`` reports).

Reproducibility. Everything random is seeded from ``TrainConfig.seed``: torch (action noise,
minibatch order, initialisation), numpy and python RNGs, and the environments'
``reset(seed=...)`` at the start of the run. A checkpoint holds, besides the networks, the
optimiser, the normalisers and the RNG streams, the episodes in progress: the env's state
(``env.get_state()``: MuJoCo's full physics state of every robot, the episode clocks, each
env's random generator), the last observation, the agent's recurrent state (the CPG state)
and the episode statistics. Checkpointing therefore neither resets nor cuts an episode, and a
resumed run continues exactly where the checkpoint was taken: it equals the uninterrupted run
bit for bit (MuJoCo; PyBullet restores joint states but not its contact caches).
"""

from __future__ import annotations

import contextlib
import json
import math
import random
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import torch

from cpg_actor.agents import get_agent_spec
from cpg_actor.checkpoint import (
    CHECKPOINT_FORMAT,
    CHECKPOINT_VERSION,
    atomic_save,
    atomic_write_text,
    check_checkpoint_run,
    load_checkpoint,
    rng_state,
    set_rng_state,
)
from cpg_actor.config import TrainConfig
from cpg_actor.device import resolve_device
from cpg_actor.episodes import EpisodeLog, EpisodeStats
from cpg_actor.evaluation import evaluation_row
from cpg_actor.machine import usable_cores
from cpg_actor.policy import Policy
from cpg_actor.ppo import (
    PPO,
    NonFiniteLossError,
    RewardNormalizer,
    RolloutStorage,
    RunningNormalizer,
    compile_generation,
    compile_reproducibly,
)
from cpg_actor.progress import evaluation_text, make_progress, metrics_text, return_text
from cpg_actor.robots.common.torch_env import TorchVectorEnv
from cpg_actor.run_log import RunLog

WARM_START_SEED_KEY = 2**31  # derived_seed(seed, this) seeds the warm start's environments
EVAL_SEED_KEY = 2**31 + 1  # derived_seed(seed, this) resets the evaluation envs, every time


class TrainingDiverged(RuntimeError):
    """A loss became NaN/inf; the run stopped and the last good checkpoint was kept."""


def derived_seed(seed: int, iteration: int) -> int:
    """The environments' reset seed after ``iteration`` iterations of a run seeded ``seed``."""
    return int(np.random.SeedSequence([seed, iteration]).generate_state(1)[0])


def seed_everything(seed: int) -> None:
    random.seed(seed)
    np.random.seed(seed % 2**32)  # noqa: NPY002 (third-party code may use the global RNG)
    torch.manual_seed(seed)


class Runner:
    """Builds env, agent, normaliser and PPO from a :class:`TrainConfig` and trains.

    ``run_dir`` (optional) receives checkpoints, ``metrics.jsonl`` and TensorBoard events;
    ``env`` and ``eval_env`` replace the agent spec's environment factory (tests).
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
        if env is not None and eval_env is None and config.eval_interval > 0:
            raise ValueError(
                "a Runner given its own env needs an eval_env too (the evaluation envs), "
                "or a config with eval_interval=0"
            )
        self.config = config
        self.run_dir = Path(run_dir) if run_dir is not None else None
        self.show_progress = progress
        self.progress_interval = progress_interval  # seconds between plain-text progress lines
        self.run_log = RunLog(self.run_dir, tensorboard)
        torch.set_num_threads(config.torch_threads)
        self.device = resolve_device(config.device)
        seed_everything(config.seed)
        self.spec = get_agent_spec(config.agent)
        if self.spec.trainer != "ppo":
            raise ValueError(
                f"agent '{config.agent}' is trained by {self.spec.trainer}, not PPO; use "
                "cpg_actor.es_runner.ESRunner (cpg-actor train picks it)"
            )
        self.env = TorchVectorEnv(
            env
            if env is not None
            else self.spec.make_env(
                config.num_envs, config.env, config.env_threads, config.agent_config
            ),
            self.device,
        )
        if self.env.num_envs != config.num_envs:
            raise ValueError(
                f"the env has {self.env.num_envs} sub-envs, the config {config.num_envs}"
            )
        action_space = self.env.single_action_space
        self.action_low = np.asarray(action_space.low, dtype=np.float32)
        self.action_high = np.asarray(action_space.high, dtype=np.float32)
        obs_dim = int(self.env.single_observation_space.shape[0])
        self.agent = self.spec.build(config.agent_config, self.env)
        self.agent.to(self.device)
        if config.ppo.bptt_steps > 1 and math.prod(self.agent.state_shape) == 0:
            raise ValueError(
                f"ppo.bptt_steps={config.ppo.bptt_steps} needs an agent with a recurrent state "
                f"(a CPG agent); '{config.agent}' has none: use 1"
            )
        self.normalizer = RunningNormalizer(obs_dim).to(self.device)
        self.policy = Policy(
            self.agent,
            self.normalizer,
            self.action_low,
            self.action_high,
            config.ppo.normalize_observations,
        )
        self.reward_normalizer = RewardNormalizer(config.num_envs, config.ppo.gamma)
        self.reward_normalizer.to(self.device)
        if config.ppo.compile:  # the rollout's policy step and reward scaling, not only the loss
            self.policy.compile()
            self.reward_normalizer.forward = compile_reproducibly(self.reward_normalizer.forward)
        self.eval_env = eval_env  # None: built at the first evaluation
        self.ppo = PPO(self.agent, config.ppo)
        self.storage = RolloutStorage(
            config.ppo.num_steps,
            config.num_envs,
            obs_dim,
            self.agent.sample_dim,
            tuple(self.agent.state_shape),
            self.device,
        )
        self.iteration = 0
        # env steps so far; a run that counts its start gait's search begins at its steps
        self.global_step = config.search_steps
        self.train_wall = 0.0  # seconds of collection + update, over the whole run
        self.env_seed: int | None = None
        # the rollout never waits for the device (no host sync per control step) when the env
        # hands over device tensors itself (MJX) or torch runs on an accelerator: the episode
        # log and the check of the actions then sync once per rollout
        self.sync_free = self.device.type != "cpu" or hasattr(self.env.unwrapped, "step_tensors")
        self.episodes = EpisodeLog(config.num_envs, deferred=self.sync_free)
        self._episodes_started = False
        self._resumed = False  # loaded from a checkpoint: no warm start, no "before" again
        # compile_generation() when this runner's compiled functions were last all built and
        # run with their guards checked (after an iteration); None: not yet
        self._warm_generation: int | None = None

    # -- episodes ----------------------------------------------------------------------------
    def start_episodes(self) -> None:
        """Reset every environment and every agent state (at the start of a run)."""
        self.env_seed = derived_seed(self.config.seed, self.iteration)
        self.obs, _ = self.env.reset(seed=self.env_seed)
        self.policy.reset(self.config.num_envs)
        self.reward_normalizer.reset()
        self.episodes.running = EpisodeStats.zeros(self.config.num_envs, self.device)
        self._episodes_started = True

    def normalize(self, obs: torch.Tensor, update: bool) -> torch.Tensor:
        return self.policy.normalize(obs, update)

    @property
    def agent_state(self) -> torch.Tensor:
        """Every training env's recurrent (CPG) state, ``(N, *state_shape)``."""
        return self.policy.state

    @property
    def skips_guard_checks(self) -> bool:
        """Whether :meth:`compiled_calls` skips dynamo's guard checks now."""
        cfg = self.config.ppo
        warm = self._warm_generation is not None and self._warm_generation == compile_generation()
        return cfg.compile and cfg.skip_guard_checks and self.device.type == "cpu" and warm

    @contextlib.contextmanager
    def compiled_calls(self) -> Iterator[None]:
        """The context of the rollout's and the update's compiled calls (``ppo.compile``).

        Before every call of a compiled function dynamo checks its guards (the inputs' shapes,
        dtypes and strides, the global settings, the module attributes the function read), a
        cost paid at every call. Once this runner has made one iteration, every compiled
        function of its loop is built for the shapes and settings the loop uses, and they do not
        change during a run; with ``ppo.skip_guard_checks`` (the default, CPU only) the calls
        then skip the checks (``torch.compiler.set_stance(skip_guard_eval_unsafe=True)``: the
        guards that told the cached variants of a function apart are still checked, a call that
        matches no variant raises instead of compiling one, and the compiled code asserts its
        inputs' sizes and strides). The same compiled code runs, so training computes the same
        numbers. After dynamo has forgotten its compiled functions (a new compiled :class:`PPO`
        in this process) the next iteration checks them again."""
        if not self.skips_guard_checks:
            yield
            return
        with torch.compiler.set_stance(skip_guard_eval_unsafe=True):
            try:
                yield
            except RuntimeError as error:
                if "skip_guard_eval_unsafe" not in str(error):
                    raise
                raise RuntimeError(
                    "a compiled function of the training loop had to be compiled again after "
                    "the run's first iteration, which ppo.skip_guard_checks assumes never "
                    "happens (did something call torch.compiler.reset() or change torch's "
                    "threads mid-run?); train with --set ppo.skip_guard_checks=false. "
                    f"torch: {error}"
                ) from None

    def collect(self) -> dict[str, float]:
        """One rollout of ``ppo.num_steps`` control steps in every environment."""
        with self.compiled_calls():
            return self._collect()

    @torch.no_grad()
    def _collect(self) -> dict[str, float]:
        cfg = self.config
        self.storage.clear()
        self._sim_time = 0.0
        # sync-free: whether every action so far was finite, on the device, checked once below
        self._finite_actions = torch.ones((), dtype=torch.bool, device=self.device)
        for _ in range(cfg.ppo.num_steps):
            self.collect_step()
        if self.sync_free:  # the rollout's one wait for the device, with the episode log's
            self.episodes.flush()
            if not bool(self._finite_actions):
                raise TrainingDiverged(
                    f"iteration {self.iteration + 1}: the policy's actions became NaN or inf "
                    f"during the rollout. Last good checkpoint: {self.last_checkpoint_path()}"
                )

        last_values = self.agent.value(self.normalize(self.obs, update=False), self.agent_state)
        self.storage.compute_returns(last_values, cfg.ppo.gamma, cfg.ppo.gae_lambda)
        return {"simulation_time": self._sim_time}

    def collect_step(self) -> None:
        """One control step of the rollout in every env: act, step, store, track episodes.
        With :attr:`sync_free` it never waits for the device (tested on JAX's CPU backend)."""
        cfg = self.config
        acted = self.policy.act(
            self.obs, deterministic=False, update_normalizer=True, tensor_action=True
        )
        step = acted.agent
        start = time.perf_counter()
        if self.sync_free:  # the env's check of the actions would wait: checked per rollout
            self._finite_actions &= torch.isfinite(acted.action).all()
            out = self.env.step(acted.action, check_finite=False)
        else:
            out = self.env.step(acted.action)
        self._sim_time += time.perf_counter() - start

        done = out.terminated | out.truncated
        final_values = torch.zeros(cfg.num_envs, device=self.device)
        bootstrap = out.truncated & ~out.terminated
        if self.sync_free:  # no sync with the host: every env's, kept where cut
            final_obs = self.normalize(out.final_obs, update=False)
            cut_values = self.agent.value(final_obs, step.next_state)
            final_values = torch.where(bootstrap, cut_values, final_values)
        elif bootstrap.any():  # the value of a cut episode's last state
            rows = bootstrap.nonzero().squeeze(-1)
            final_obs = self.normalize(out.final_obs[rows], update=False)
            final_values[rows] = self.agent.value(final_obs, step.next_state[rows])
        rewards = out.reward.to(torch.float32)
        if cfg.ppo.normalize_rewards:
            rewards = self.reward_normalizer(rewards, done)
        self.storage.add_policy_step(acted, rewards, out.terminated, out.truncated, final_values)
        self.policy.end_episodes(done)
        self.obs = out.obs
        self.episodes.track(out, done)

    # -- training ----------------------------------------------------------------------------
    def learn(self, stop_when: Callable[[dict[str, float]], bool] | None = None) -> None:
        """Train to ``config.total_steps``; checkpoint every ``checkpoint_interval`` iterations.

        ``stop_when(evaluation)``, if given, is called with each evaluation's scalars
        (``eval/return``, ``eval/hop_height``, ...); training stops after the first one for
        which it returns True (with a checkpoint, if the run has a directory)."""
        cfg = self.config
        num_iterations = cfg.num_iterations
        if self.run_dir is not None:
            self.run_dir.mkdir(parents=True, exist_ok=True)
        fresh = self.iteration == 0 and not self._resumed  # a new run, not one resumed at 0
        if fresh and self.spec.warm_start is not None:
            self.run_warm_start()
        if not self._episodes_started:
            self.start_episodes()
        if fresh and cfg.eval_interval > 0:
            self.log_evaluation()  # the untrained (or warm-started) agent
        if fresh and self.run_dir is not None:
            self.save_checkpoint()  # the untrained (or warm-started) agent: a "before"
        progress = self._make_progress(num_iterations)
        try:
            while self.iteration < num_iterations:
                start = time.perf_counter()
                self.ppo.schedule(self.iteration, num_iterations)
                collect_info = self.collect()
                collect_time = time.perf_counter() - start
                start_learn = time.perf_counter()
                try:
                    stats = self.update()
                except NonFiniteLossError as error:
                    raise TrainingDiverged(
                        f"iteration {self.iteration + 1}: {error}. "
                        f"Last good checkpoint: {self.last_checkpoint_path()}"
                    ) from None
                learn_time = time.perf_counter() - start_learn
                self.iteration += 1
                self.global_step += cfg.steps_per_iteration
                self.train_wall += collect_time + learn_time
                sps = cfg.steps_per_iteration / (collect_time + learn_time)
                timing = {
                    "SPS": sps,
                    "collection": collect_time,
                    "simulation": collect_info["simulation_time"],
                    "inference": collect_time - collect_info["simulation_time"],
                    "learning": learn_time,
                }
                last = self.iteration == num_iterations
                evaluation = None
                if cfg.eval_interval > 0 and (self.iteration % cfg.eval_interval == 0 or last):
                    evaluation = self.run_evaluation()
                if self.iteration % cfg.log_interval == 0 or last or evaluation is not None:
                    self.log(stats, timing, evaluation)
                stop = evaluation is not None and stop_when is not None and stop_when(evaluation)
                if evaluation is not None:
                    self._evaluation_text = evaluation_text(evaluation)
                if progress is not None:
                    progress.update(
                        self._task,
                        completed=self.global_step,
                        sps=f"{sps:,.0f}",
                        ret=return_text(self.episodes.mean("return")),
                        metrics=metrics_text(self.episodes.env_metrics()),
                        evaluation=getattr(self, "_evaluation_text", ""),
                    )
                at_interval = self.iteration % cfg.checkpoint_interval == 0
                if self.run_dir is not None and (at_interval or last or stop):
                    self.save_checkpoint()
                if stop:
                    break
        finally:
            if progress is not None:
                progress.stop()
            self.run_log.flush()

    def update_threads(self) -> int:
        """Torch threads for the PPO update (``config.update_threads``; see TrainConfig)."""
        cfg = self.config
        if cfg.update_threads is not None:
            return cfg.update_threads
        minibatch = cfg.steps_per_iteration // cfg.ppo.num_minibatches
        return usable_cores() if minibatch >= 1024 else cfg.torch_threads

    def update(self) -> dict[str, float]:
        """The PPO update of the collected rollout, on :meth:`update_threads` torch threads
        (the simulator's threads are idle meanwhile); the rollout runs on ``torch_threads``."""
        torch.set_num_threads(self.update_threads())
        try:
            with self.compiled_calls():
                stats = self.ppo.update(self.storage)
        finally:
            torch.set_num_threads(self.config.torch_threads)
        self._warm_generation = compile_generation()  # a whole iteration has run
        return stats

    def run_warm_start(self) -> list[float]:
        """The agent's supervised warm start (e.g. cho2019-warm), before any PPO iteration.

        Its environment seed is derived from ``(seed, WARM_START_SEED_KEY)``; the episodes it
        ran are discarded (:meth:`start_episodes` resets every env afterwards). The loss of
        each epoch goes to TensorBoard (``warm_start/loss``) and ``RUN_DIR/warm_start.json``.
        """
        cfg = self.config
        seed = derived_seed(cfg.seed, WARM_START_SEED_KEY)
        normalizer = self.normalizer if cfg.ppo.normalize_observations else None
        losses = self.spec.warm_start(self.agent, normalizer, self.env.unwrapped, cfg, seed)
        self._episodes_started = False
        if self.show_progress:
            print(
                f"warm start: {len(losses)} epochs, loss {losses[0]:.4g} -> {losses[-1]:.4g}",
                flush=True,
            )
        if self.run_dir is not None:
            self.run_dir.mkdir(parents=True, exist_ok=True)
            atomic_write_text(json.dumps({"loss": losses}) + "\n", self.run_dir / "warm_start.json")
            for epoch, loss in enumerate(losses):
                self.run_log.scalar("warm_start/loss", loss, epoch)
        return losses

    def run_evaluation(self) -> dict[str, float]:
        """Deterministic episodes on the evaluation envs (see the module docstring)."""
        cfg = self.config
        start = time.perf_counter()
        if self.eval_env is None:
            self.eval_env = self.spec.make_env(
                cfg.eval_episodes, cfg.env, cfg.env_threads, cfg.agent_config
            )
        # a policy of its own (the same agent and normaliser): the training envs' CPG states
        # stay untouched
        policy = Policy(
            self.agent,
            self.normalizer,
            self.action_low,
            self.action_high,
            cfg.ppo.normalize_observations,
        )
        row = evaluation_row(
            policy,
            self.eval_env,
            seed=derived_seed(cfg.seed, EVAL_SEED_KEY),
            control_dt=float(cfg.env.control_dt),
            max_steps=int(getattr(cfg.env, "episode_steps", 10_000)),
        )
        row["time/eval"] = time.perf_counter() - start
        return row

    def log_evaluation(self) -> dict[str, float]:
        """Evaluate now and log it alone (a metrics row of the current iteration)."""
        evaluation = self.run_evaluation()
        self._evaluation_text = evaluation_text(evaluation)
        self.last_evaluation = evaluation
        self.run_log.write(
            self.iteration,
            self.global_step,
            dict(evaluation, **{"time/train_wall": self.train_wall}),
        )
        return evaluation

    def _make_progress(self, num_iterations: int):
        if not self.show_progress:
            return None
        total = self.config.search_steps + num_iterations * self.config.steps_per_iteration
        progress, self._task = make_progress(
            self.config.agent,
            total,
            self.global_step,
            self.progress_interval,
            getattr(self, "_evaluation_text", ""),
        )
        return progress

    # -- logging -----------------------------------------------------------------------------
    def scalars(self, stats: dict[str, float], timing: dict[str, float]) -> dict[str, float]:
        row = self.episodes.scalars()  # return, length, the env's metrics, reward terms
        row["charts/SPS"] = timing["SPS"]
        row["charts/learning_rate"] = stats["learning_rate"]
        if "cpg_learning_rate" in stats:  # ppo.cpg_learning_rate's group
            row["charts/cpg_learning_rate"] = stats["cpg_learning_rate"]
        for key in (
            "policy_loss",
            "value_loss",
            "entropy",
            "approx_kl",
            "kl",
            "clipfrac",
            "explained_variance",
        ):
            if key in stats:
                row[f"losses/{key}"] = stats[key]
        for key in ("collection", "simulation", "inference", "learning"):
            row[f"time/{key}"] = timing[key]
        row["time/train_wall"] = self.train_wall
        row.update(self.agent.log_scalars())  # the agent's own: log-std, CPG parameters, ...
        return row

    def log(
        self,
        stats: dict[str, float],
        timing: dict[str, float],
        evaluation: dict[str, float] | None = None,
    ) -> None:
        row = self.scalars(stats, timing)
        if evaluation is not None:
            row.update(evaluation)
            self.last_evaluation = evaluation
        self.last_row = row
        self.run_log.write(self.iteration, self.global_step, row)
        if self.run_log.use_tensorboard and self.iteration % self.config.histogram_interval == 0:
            # the agent's own (paper Fig. 5: CPG parameters, the feedback's output layer)
            self.run_log.histograms(self.global_step, self.agent.log_histograms())

    # -- checkpoints -------------------------------------------------------------------------
    def checkpoint_dir(self) -> Path:
        assert self.run_dir is not None
        return self.run_dir / "checkpoints"

    def last_checkpoint_path(self) -> Path | None:
        if self.run_dir is None:
            return None
        path = self.checkpoint_dir() / "last.pt"
        return path if path.exists() else None

    def state_dict(self) -> dict[str, Any]:
        return {
            "format": CHECKPOINT_FORMAT,
            "version": CHECKPOINT_VERSION,
            "agent": self.config.agent,
            "config": self.config.to_dict(),
            "iteration": self.iteration,
            "global_step": self.global_step,
            "agent_state": self.agent.state_dict(),
            "normalizer": self.normalizer.state_dict(),
            "reward_normalizer": self.reward_normalizer.state_dict(),
            "train_wall": self.train_wall,
            "optimizer": self.ppo.optimizer.state_dict(),
            "learning_rate": self.ppo.learning_rate,
            "rng": rng_state(),
            "env_seed": self.env_seed,
            "recent": self.episodes.recent_state(),
            "episodes": self.episodes_state(),
        }

    def episodes_state(self) -> dict[str, Any] | None:
        """The episodes in progress (see the module docstring); None if the env cannot save
        its state (a resumed run then starts new episodes)."""
        if not self._episodes_started or not hasattr(self.env.unwrapped, "get_state"):
            return None
        return {
            "env": self.env.get_state(),
            "obs": self.obs.cpu().clone(),
            "agent_state": self.policy.state.cpu().clone(),
            "statistics": self.episodes.running.state_dict(),
            "discounted_returns": self.reward_normalizer.discounted.cpu().clone(),
        }

    def restore_episodes(self, state: dict[str, Any]) -> None:
        """Continue the episodes saved by :meth:`episodes_state`."""
        try:
            self.env.set_state(state["env"])
            obs, agent_state = state["obs"], state["agent_state"]
            if obs.shape != (self.config.num_envs, self.env.single_observation_space.shape[0]):
                raise ValueError(f"observations of shape {tuple(obs.shape)}")
            if agent_state.shape != (self.config.num_envs, *self.agent.state_shape):
                raise ValueError(f"agent states of shape {tuple(agent_state.shape)}")
            running = EpisodeStats.from_state_dict(state["statistics"], self.device)
            discounted = state["discounted_returns"]
            if discounted.shape != self.reward_normalizer.discounted.shape:
                raise ValueError(f"discounted returns of shape {tuple(discounted.shape)}")
            self.reward_normalizer.discounted.copy_(discounted)
        except (KeyError, TypeError, AttributeError, RuntimeError, ValueError) as error:
            raise ValueError(
                f"the checkpoint's episodes do not fit this run's environments: {error}"
            ) from None
        self.episodes.running = running
        self.obs = obs.to(self.device).clone()
        self.policy.state = agent_state.to(self.device).clone()
        self._episodes_started = True

    def save_checkpoint(self) -> Path:
        data = self.state_dict()
        path = self.checkpoint_dir() / f"iter_{self.iteration:06d}.pt"
        atomic_save(data, path)
        atomic_save(data, self.checkpoint_dir() / "last.pt")
        return path

    def load_checkpoint(self, path: Path) -> None:
        """Continue training from ``path`` (networks, optimiser, normalisers, RNG streams,
        counters and the episodes in progress). To act with a trained agent, see
        :func:`cpg_actor.policy.load_policy`."""
        data = load_checkpoint(path)
        check_checkpoint_run(path, data, self.config.agent)
        try:
            self.agent.load_state_dict(data["agent_state"])
            self.normalizer.load_state_dict(data["normalizer"])
        except RuntimeError as error:
            raise ValueError(
                f"checkpoint {path} does not match this agent's networks: {error}"
            ) from None
        self.ppo.optimizer.load_state_dict(data["optimizer"])
        self.ppo.set_learning_rate(data["learning_rate"])
        if "reward_normalizer" in data:  # absent from checkpoints of earlier versions
            self.reward_normalizer.load_state_dict(data["reward_normalizer"])
        self.train_wall = float(data.get("train_wall", 0.0))
        self._resumed = True
        self.iteration = data["iteration"]
        self.global_step = data["global_step"]
        self.run_log.purge_step = self.global_step + 1  # TensorBoard drops what came after
        self.episodes.load_recent(data["recent"])
        set_rng_state(data["rng"])
        self.env_seed = data.get("env_seed")
        episodes = data.get("episodes")
        if episodes is not None and hasattr(self.env.unwrapped, "set_state"):
            self.restore_episodes(episodes)
        else:  # a checkpoint without episodes (an env that cannot save them): new ones
            self.start_episodes()

    def close(self) -> None:
        self.run_log.close()
        self.env.close()
        if self.eval_env is not None:
            self.eval_env.close()
            self.eval_env = None
