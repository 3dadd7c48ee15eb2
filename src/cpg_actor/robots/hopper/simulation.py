"""K hoppers stepped together on a CPU simulator: a control step is ``decimation`` physics
substeps of the backend (which runs the joint actuators at every substep), then the task of
:mod:`cpg_actor.robots.hopper.task` (observation, reward, termination), which the MJX env runs
too. :class:`HopperEnv` is K = 1 and :class:`HopperVectorEnv` is K = N of this same code, which
is why they produce identical trajectories.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cpg_actor.robots.common.perturbation import CommandDelay, EpisodeDraws, push_force
from cpg_actor.robots.hopper import task
from cpg_actor.robots.hopper.backends import make_backend
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.task import NOMINAL_POSE


@dataclass
class StepResult:
    """One control step of K robots (arrays have K rows)."""

    obs: np.ndarray  # (K, 8) float32
    reward: np.ndarray  # (K,) float64
    terminated: np.ndarray  # (K,) bool: simulation blow-up
    truncated: np.ndarray  # (K,) bool: time limit
    reward_terms: dict[str, np.ndarray]  # r1..r5, (K,) each
    hip_height: np.ndarray  # (K,)
    foot_height: np.ndarray  # (K,) lowest point of the foot sphere above the ground
    joint_torque: np.ndarray  # (K, 2) applied torque, mean over the control step
    desired_position: np.ndarray  # (K, 2)
    measured_position: np.ndarray  # (K, 2)
    measured_velocity: np.ndarray  # (K, 2) rad/s, the joints' true velocity
    foot_position: np.ndarray  # (K, 1, 3) the foot sphere's centre in the world (m)


class HopperSimulation:
    """K hoppers on one simulator backend (see ``docs/hopper.md``), perturbed as the config's
    ``perturbation`` says: the backend built with its payload, friction and motor strength,
    the commands delayed by its latency (:class:`CommandDelay`), its push and sensor noise
    drawn per env (:class:`EpisodeDraws`, seeded by :meth:`seed_perturbations`); under
    ``randomize``, each robot's episode perturbation drawn there too."""

    def __init__(
        self, config: HopperConfig, num_robots: int = 1, num_threads: int | None = None
    ) -> None:
        config.validate()
        self.config = config
        self.num_robots = int(num_robots)
        self.backend = make_backend(config, self.num_robots, num_threads)
        self.desired = np.tile(NOMINAL_POSE, (self.num_robots, 1))
        self.elapsed_steps = np.zeros(self.num_robots, dtype=np.int64)
        perturbation, randomize = config.perturbation, config.randomize
        latency = perturbation.substeps(config.decimation)
        longest = round(randomize.latency[1] * config.decimation)
        self.delay = None
        if latency or longest:
            self.delay = CommandDelay(latency, config.decimation, self.num_robots, 2, longest)
        self.draws = EpisodeDraws(config, self.num_robots, task.SENSOR_NOISE)
        self.push_force = push_force(perturbation, config.control_dt)[2]  # along the rail
        self.pushed = np.zeros(self.num_robots, dtype=bool)

    def seed_perturbations(self, seeds) -> None:
        """The perturbation's generators, robot i's from ``seeds[i]`` (its env's seed)."""
        self.draws.seed(seeds)

    # -- reset -------------------------------------------------------------------------------
    def reset_robots(self, index: np.ndarray, joint_noise: np.ndarray) -> None:
        """Nominal pose + ``joint_noise`` (k, 2), foot on the ground, at rest; p_d = nominal."""
        index = np.atleast_1d(np.asarray(index, dtype=np.int64))
        noise = np.asarray(joint_noise, dtype=np.float64).reshape(-1, 2)
        qpos = task.start_qpos(noise, self.config.reset_clearance)
        self.backend.reset_robots(index, qpos, np.zeros((len(index), 3)))
        self.desired[index] = NOMINAL_POSE
        self.elapsed_steps[index] = 0
        self.draws.start(index)
        if self.config.randomize.active:  # each robot's episode perturbation
            self._perturb(index)
        if self.delay is not None:
            self.delay.reset(index, NOMINAL_POSE)

    def _perturb(self, index: np.ndarray) -> None:
        """The robots ``index`` simulated under their episode perturbations (randomised
        training): their physics and their latency."""
        episodes = [self.draws.episodes[i] for i in index]
        self.backend.perturb_robots(
            index, np.array([p.payload for p in episodes]),
            np.array([p.ground_friction(self.config.foot_friction) for p in episodes]),
            np.array([p.motor_strength for p in episodes]),
        )  # fmt: skip
        if self.delay is not None:
            self.delay.set_latency(index, [p.substeps(self.config.decimation) for p in episodes])

    def get_state(self) -> dict[str, np.ndarray]:
        """The simulator state, the desired positions being tracked and the episode clocks
        (with a perturbation: the commands on their way and each episode's push step)."""
        state = {
            "backend": self.backend.get_state(),
            "desired": self.desired.copy(),
            "elapsed_steps": self.elapsed_steps.copy(),
        }
        if self.delay is not None:
            state["delayed"] = self.delay.get_state()
        if self.draws.active:
            state["push_step"] = self.draws.push_step.copy()
        return state

    def perturbation_state(self) -> dict:
        """The perturbation's generators and episode draws (plain values), or {} if none."""
        return self.draws.get_state() if self.draws.active else {}

    def set_perturbation_state(self, state: dict) -> None:
        """Restore :meth:`perturbation_state` (after :meth:`set_state`): the generators, and
        under randomised training every robot's episode perturbation, physics included."""
        if not state:
            return
        self.draws.set_state(state)
        if self.config.randomize.active:
            self._perturb(np.arange(self.num_robots))

    def set_state(self, state: dict[str, np.ndarray]) -> None:
        self.backend.set_state(np.asarray(state["backend"]))
        np.copyto(self.desired, np.asarray(state["desired"], dtype=np.float64))
        np.copyto(self.elapsed_steps, np.asarray(state["elapsed_steps"], dtype=np.int64))
        if self.delay is not None and "delayed" in state:
            self.delay.set_state(state["delayed"])
        if "push_step" in state:
            np.copyto(self.draws.push_step, np.asarray(state["push_step"], dtype=np.int64))

    def sample_noise(self, rng: np.random.Generator) -> np.ndarray:
        """Uniform joint noise for one reset, drawn from ``rng``: (2,)."""
        scale = self.config.reset_noise
        return rng.uniform(-scale, scale, size=2)

    # -- step --------------------------------------------------------------------------------
    def step(self, desired: np.ndarray) -> StepResult:
        """Track ``desired`` (K, 2), the agent's command low-passed by ``command_filter``, for
        one control step (``decimation`` physics substeps)."""
        backend, config = self.backend, self.config
        # the command low-passed onto the last desired positions (none at command_filter 1)
        np.copyto(self.desired, task.command_filter(self.desired, desired, config.command_filter))
        before = None
        if config.hop_reward == "apex":
            before = task.com_velocity(backend.qpos, backend.qvel)
        # the drives track the command sent `latency` steps ago (the observation and the
        # reward's tracking term keep the one sent now: what the controller knows)
        applied = self.desired if self.delay is None else self.delay.schedule(self.desired)
        push = None
        self.pushed = self.draws.pushed(self.elapsed_steps)  # (K,) the robots pushed now
        if self.pushed.any():
            push = np.where(self.pushed, self.push_force, 0.0)
        joint_torque = backend.track(applied, config.decimation, push)
        self.elapsed_steps += 1
        with np.errstate(invalid="ignore", over="ignore"):  # a blown-up robot: zeroed
            out = task.step_outcome(config, backend.qpos, backend.qvel, self.desired.copy(),
                                    joint_torque, self.elapsed_steps, config.episode_steps,
                                    before, backend.unstable())  # fmt: skip
        self.draws.observe(out["obs"])  # the sensors' noise
        return StepResult(**out)

    # -- observation -------------------------------------------------------------------------
    def observation(self, index=None) -> np.ndarray:
        """(K, 8) float32 in the order of :data:`~cpg_actor.robots.hopper.task.OBS_NAMES`, as
        the sensors read it (with a perturbation's noise on the rows ``index``, default all)."""
        with np.errstate(invalid="ignore", over="ignore"):
            obs = task.observation(self.backend.qpos, self.backend.qvel, self.desired)
        return self.draws.observe(obs, index)

    def foot_height(self) -> np.ndarray:
        """(K,) height of the lowest point of the foot sphere (0: touching the ground)."""
        return task.foot_height(self.backend.qpos)

    def close(self) -> None:
        self.backend.close()
