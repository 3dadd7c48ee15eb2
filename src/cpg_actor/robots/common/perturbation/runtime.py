"""A perturbation at run time, shared by every robot's env: :class:`CommandDelay` (latency),
:class:`EpisodeDraws` (each env's generator: push steps, sensor noise, randomised training's
draws) and :func:`push_force`."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from cpg_actor.robots.common.perturbation.values import PUSH_DIRECTIONS, Perturbation

# mixed into each env's seed for the perturbations' own generators: their draws never touch
# the env's (start poses, commands)
SEED_KEY = 0x7E57B0D5


class CommandDelay:
    """The commands of N robots applied late: ``schedule(desired)`` takes this step's commands
    (N, J) and gives what the drives track at each of the step's ``decimation`` substeps
    (N, decimation, J). Robot i's commands arrive ``latency[i]`` physics substeps late
    (:meth:`set_latency`; a perturbation's for all at first, ``longest`` substeps at most).
    Before an episode's first command arrives the drives track its start command
    (:meth:`reset`)."""

    def __init__(self, latency: int, decimation: int, num_envs: int, num_joints: int,
                 longest: int | None = None) -> None:  # fmt: skip
        self.decimation = decimation
        longest = latency if longest is None else max(longest, latency)
        # the last commands, oldest first: enough for the longest delay
        self.history = np.zeros((longest // decimation + 2, num_envs, num_joints))
        self.latency = np.full(num_envs, latency, dtype=np.int64)
        self._rows = np.arange(num_envs)

    @property
    def steps(self) -> np.ndarray:
        """(N,) whole control steps of each robot's delay."""
        return self.latency // self.decimation

    def set_latency(self, index, substeps) -> None:
        self.latency[index] = substeps

    def reset(self, index, command) -> None:
        """Robots ``index`` start an episode with the drives on ``command`` (k, J) or (J,)."""
        self.history[:, index] = command

    def schedule(self, desired: np.ndarray) -> np.ndarray:
        self.history[:-1] = self.history[1:].copy()
        self.history[-1] = desired
        steps, substeps = np.divmod(self.latency, self.decimation)
        newest = len(self.history) - 1
        before = self.history[newest - steps - 1, self._rows]  # the step before's command
        arrived = self.history[newest - steps, self._rows]  # this step's, `steps` steps ago
        early = np.arange(self.decimation)[None, :] < substeps[:, None]  # (N, decimation)
        return np.where(early[:, :, None], before[:, None], arrived[:, None])

    def get_state(self) -> np.ndarray:
        return self.history.copy()

    def set_state(self, history: np.ndarray) -> None:
        np.copyto(self.history, np.asarray(history, dtype=np.float64))


def perturbation_seed(seed: int | None) -> np.random.SeedSequence | None:
    """The seed of an env's perturbation generator, from the env's own seed (None: random)."""
    return None if seed is None else np.random.SeedSequence([SEED_KEY, int(seed)])


class EpisodeDraws:
    """The random part of the perturbations of N envs: each env's generator of its own (seeded
    from the env's seed by :func:`perturbation_seed`), each episode's perturbation under
    randomised training, the control step of each episode's push and the sensor noise. With
    nothing to draw it does nothing."""

    def __init__(self, config: Any, num_envs: int, sensor_noise: Sequence[float]) -> None:
        perturbation, randomize = config.perturbation, config.randomize
        self.perturbation, self.randomize = perturbation, randomize
        self.decimation = config.decimation
        self.active = perturbation.random or randomize.active
        self.num_envs = num_envs
        first, last = (round(t / config.control_dt) for t in perturbation.push_time)
        self.window = (first, min(last, config.episode_steps - 1))  # a push in every episode
        self.sensor_noise = np.asarray(sensor_noise, dtype=np.float64)
        self.noisy = np.flatnonzero(self.sensor_noise > 0)
        self.rngs: list[np.random.Generator] = []
        self.push_step = np.full(num_envs, -1, dtype=np.int64)
        # randomised training's pushes: the control step of each env's next kick
        self.control_dt = config.control_dt
        self.kick_step = np.full(num_envs, -1, dtype=np.int64)
        # each env's episode perturbation (randomised training: drawn by start())
        self.episodes = [perturbation] * num_envs

    def seed(self, seeds: Sequence[int | None]) -> None:
        """New generators, env i's from ``seeds[i]``."""
        if self.active:
            self.rngs = [np.random.default_rng(perturbation_seed(s)) for s in seeds]

    def start(self, index) -> np.ndarray:
        """Draw the episodes the envs ``index`` start: under randomised training their
        perturbations (:attr:`episodes`), then their push steps. Returns ``index`` as an
        array."""
        index = np.atleast_1d(index)
        if not self.active:
            return index
        for i in index:
            rng = self.rngs[i]
            if self.randomize.active:
                self.episodes[i] = self.randomize.draw(rng, self.decimation, self.perturbation)
            if self.perturbation.push:
                self.push_step[i] = rng.integers(self.window[0], self.window[1] + 1)
            if self.randomize.pushes:
                self.kick_step[i] = self._interval(rng)
        return index

    def _interval(self, rng: np.random.Generator) -> int:
        """Control steps to a training push: ``randomize.push_interval`` s drawn (>= 1)."""
        low, high = self.randomize.push_interval
        seconds = rng.uniform(low, high) if high > low else low
        return max(1, round(seconds / self.control_dt))

    def kicks(self, elapsed: np.ndarray) -> np.ndarray | None:
        """(N, 2) the horizontal velocity kicks (m/s, world frame) of randomised training's
        pushes due after ``elapsed`` (N,) control steps (zero for the others), each of a size
        drawn in ``randomize.push_velocity`` in a direction drawn uniformly, the next push
        drawn ``randomize.push_interval`` s later; None when none is due."""
        if not (self.active and self.randomize.pushes):
            return None
        due = np.flatnonzero(self.kick_step == elapsed)
        if due.size == 0:
            return None
        kicks = np.zeros((self.num_envs, 2))
        low, high = self.randomize.push_velocity
        for i in due:
            rng = self.rngs[i]
            size = rng.uniform(low, high) if high > low else low
            angle = rng.uniform(0.0, 2.0 * np.pi)
            kicks[i] = size * np.cos(angle), size * np.sin(angle)
            self.kick_step[i] = elapsed[i] + self._interval(rng)
        return kicks

    def pushed(self, elapsed: np.ndarray) -> np.ndarray:
        """(N,) bool: the envs pushed during the control step after ``elapsed`` steps."""
        return (self.push_step == elapsed) & self.active & (self.perturbation.push > 0.0)

    def observe(self, obs: np.ndarray, index=None) -> np.ndarray:
        """``obs`` (N, D) as the sensors read it: noise added to rows ``index`` (default all),
        in place (float32)."""
        if not self.active or self.noisy.size == 0:
            return obs
        rows = range(self.num_envs) if index is None else np.atleast_1d(index)
        for i in rows:
            level = self.episodes[i].obs_noise
            if level > 0.0:
                std = level * self.sensor_noise[self.noisy]
                obs[i, self.noisy] += self.rngs[i].normal(0.0, std).astype(obs.dtype)
        return obs

    def get_state(self) -> dict[str, Any]:
        """The generators and the episode perturbations, as plain Python values (the push
        steps, an array, are the env's to save: :attr:`push_step`)."""
        state = {"rngs": [rng.bit_generator.state for rng in self.rngs],
                 "episodes": [dataclasses.asdict(p) for p in self.episodes]}  # fmt: skip
        if self.randomize.pushes:
            state["kick_step"] = self.kick_step.tolist()
        return state

    def set_state(self, state: dict[str, Any], push_step=None) -> None:
        self.rngs = []
        for saved in state["rngs"]:
            rng = np.random.default_rng()
            rng.bit_generator.state = saved
            self.rngs.append(rng)
        if push_step is not None:
            np.copyto(self.push_step, np.asarray(push_step, dtype=np.int64))
        self.episodes = [Perturbation.from_value(dict(p)) for p in state["episodes"]]
        if "kick_step" in state:
            np.copyto(self.kick_step, np.asarray(state["kick_step"], dtype=np.int64))


def push_force(perturbation: Perturbation, control_dt: float) -> np.ndarray:
    """The push's force (3,), N, in its direction's frame: the impulse over one control step."""
    return (perturbation.push / control_dt) * np.asarray(PUSH_DIRECTIONS[
        perturbation.push_direction])  # fmt: skip
