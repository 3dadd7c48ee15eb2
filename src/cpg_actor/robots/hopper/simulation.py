"""K hoppers stepped together: reset pose, a control step of ``decimation`` physics substeps
(the backend runs the joint actuators at every substep), observation, reward, termination.
:class:`HopperEnv` is K = 1 and :class:`HopperVectorEnv` is K = N of this same code, which is
why they produce identical trajectories.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cpg_actor.robots.hopper import description as robot
from cpg_actor.robots.hopper import kinematics
from cpg_actor.robots.hopper.backends import make_backend
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.reward import apex_reward, reward_terms, total_reward

OBS_NAMES = (
    "p_m_HFE",  # measured joint positions, rad
    "p_m_KFE",
    "v_m_HFE",  # measured joint velocities, rad/s
    "v_m_KFE",
    "p_d_HFE",  # desired joint positions being tracked (the last action), rad
    "p_d_KFE",
    "hip_height",  # m, height of the hip (HFE axis) above the ground
    "hip_velocity",  # m/s, vertical, positive up
)
# where each entry comes from in the MuJoCo model's data
# (cpg_actor.deploy.export.OBSERVATION_SOURCES)
OBS_SOURCES = (
    {"source": "qpos", "index": 1},
    {"source": "qpos", "index": 2},
    {"source": "qvel", "index": 1},
    {"source": "qvel", "index": 2},
    {"source": "desired", "index": 0},
    {"source": "desired", "index": 1},
    {"source": "qpos", "index": 0},  # the rail joint's position is the hip height
    {"source": "qvel", "index": 0},
)
NOMINAL_POSE = np.array(robot.NOMINAL_POSE)
ACTION_LOW = np.array([robot.JOINT_LIMITS[j][0] for j in robot.JOINT_NAMES])
ACTION_HIGH = np.array([robot.JOINT_LIMITS[j][1] for j in robot.JOINT_NAMES])
OBS_BOUND = 1e6  # finite stand-in for non-finite values of a blown-up simulation


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


class HopperSimulation:
    """K hoppers on one simulator backend (see ``docs/hopper.md``)."""

    def __init__(
        self, config: HopperConfig, num_robots: int = 1, num_threads: int | None = None
    ) -> None:
        config.validate()
        self.config = config
        self.num_robots = int(num_robots)
        self.backend = make_backend(config, self.num_robots, num_threads)
        self.weights = config.reward_weights
        self.desired = np.tile(NOMINAL_POSE, (self.num_robots, 1))
        self.highest_standing_com = kinematics.highest_standing_com()  # the apex reward's zero
        self.elapsed_steps = np.zeros(self.num_robots, dtype=np.int64)

    # -- reset -------------------------------------------------------------------------------
    def reset_robots(self, index: np.ndarray, joint_noise: np.ndarray) -> None:
        """Nominal pose + ``joint_noise`` (k, 2), foot on the ground, at rest; p_d = nominal."""
        index = np.atleast_1d(np.asarray(index, dtype=np.int64))
        joint_pos = NOMINAL_POSE + np.asarray(joint_noise, dtype=np.float64).reshape(-1, 2)
        qpos = np.empty((len(index), 3))
        qpos[:, 0] = kinematics.standing_hip_height(joint_pos) + self.config.reset_clearance
        qpos[:, 1:] = joint_pos
        self.backend.reset_robots(index, qpos, np.zeros((len(index), 3)))
        self.desired[index] = NOMINAL_POSE
        self.elapsed_steps[index] = 0

    def get_state(self) -> dict[str, np.ndarray]:
        """The simulator state, the desired positions being tracked and the episode clocks."""
        return {
            "backend": self.backend.get_state(),
            "desired": self.desired.copy(),
            "elapsed_steps": self.elapsed_steps.copy(),
        }

    def set_state(self, state: dict[str, np.ndarray]) -> None:
        self.backend.set_state(np.asarray(state["backend"]))
        np.copyto(self.desired, np.asarray(state["desired"], dtype=np.float64))
        np.copyto(self.elapsed_steps, np.asarray(state["elapsed_steps"], dtype=np.int64))

    def sample_noise(self, rng: np.random.Generator) -> np.ndarray:
        """Uniform joint noise for one reset, drawn from ``rng``: (2,)."""
        scale = self.config.reset_noise
        return rng.uniform(-scale, scale, size=2)

    # -- step --------------------------------------------------------------------------------
    def step(self, desired: np.ndarray) -> StepResult:
        """Track ``desired`` (K, 2) for one control step (``decimation`` physics substeps)."""
        backend = self.backend
        np.copyto(self.desired, desired)
        apex = self.config.hop_reward == "apex"
        if apex:
            com_velocity_before = kinematics.com_vertical_velocity(
                backend.qvel[:, 0], backend.qpos[:, 1:3], backend.qvel[:, 1:3]
            )
        joint_torque = backend.track(self.desired, self.config.decimation)
        self.elapsed_steps += 1

        qpos, qvel = backend.qpos, backend.qvel
        with np.errstate(invalid="ignore", over="ignore"):  # a blown-up robot: zeroed below
            foot_velocity = kinematics.foot_velocity(qpos[:, 1:3], qvel[:, 1:3])
            foot_velocity_xy = np.stack([foot_velocity[:, 0], np.zeros(self.num_robots)], -1)
            terms = reward_terms(
                self.weights, qvel[:, 0], self.desired, qpos[:, 1:3], qvel[:, 1:3],
                joint_torque, foot_velocity_xy,
            )  # fmt: skip
            if apex:
                terms["r1"] = apex_reward(
                    self.config.apex_weight,
                    com_velocity_before,
                    kinematics.com_vertical_velocity(qvel[:, 0], qpos[:, 1:3], qvel[:, 1:3]),
                    qpos[:, 0] + kinematics.com_height_offset(qpos[:, 1:3]),
                    self.highest_standing_com,
                    self.foot_height(),
                )
        terminated = self._blown_up()
        result = StepResult(
            obs=self.observation(),
            reward=np.zeros(self.num_robots),
            terminated=terminated,
            truncated=(self.elapsed_steps >= self.config.episode_steps) & ~terminated,
            reward_terms=terms,
            hip_height=qpos[:, 0].copy(),
            foot_height=self.foot_height(),
            joint_torque=joint_torque,
            desired_position=self.desired.copy(),
            measured_position=qpos[:, 1:3].copy(),
        )
        if terminated.any():  # a blown-up robot: finite numbers, zero reward
            for value in terms.values():
                value[terminated] = 0.0
            for name in ("hip_height", "foot_height", "joint_torque", "measured_position"):
                value = getattr(result, name)
                value[terminated] = np.clip(np.nan_to_num(value[terminated]), -OBS_BOUND, OBS_BOUND)
        result.reward = total_reward(terms)
        return result

    def _blown_up(self) -> np.ndarray:
        """(K,) bool: non-finite state, absurd velocities, or the simulator reset itself."""
        qpos, qvel = self.backend.qpos, self.backend.qvel
        with np.errstate(invalid="ignore"):
            bad = ~np.isfinite(qpos).all(axis=1) | ~np.isfinite(qvel).all(axis=1)
            bad |= np.abs(qvel[:, 1:3]).max(axis=1) > self.config.blowup_joint_velocity
            bad |= np.abs(qvel[:, 0]) > self.config.blowup_hip_velocity
        bad |= self.backend.unstable()
        return bad

    # -- observation -------------------------------------------------------------------------
    def observation(self) -> np.ndarray:
        """(K, 8) float32 in the order of :data:`OBS_NAMES`."""
        qpos, qvel = self.backend.qpos, self.backend.qvel
        obs = np.empty((self.num_robots, 8))
        obs[:, 0:2] = qpos[:, 1:3]
        obs[:, 2:4] = qvel[:, 1:3]
        obs[:, 4:6] = self.desired
        obs[:, 6] = qpos[:, 0]
        obs[:, 7] = qvel[:, 0]
        if not np.isfinite(obs).all() or np.abs(obs).max() > OBS_BOUND:
            obs = np.clip(np.nan_to_num(obs, nan=0.0), -OBS_BOUND, OBS_BOUND)
        return obs.astype(np.float32)

    def foot_height(self) -> np.ndarray:
        """(K,) height of the lowest point of the foot sphere (0: touching the ground)."""
        qpos = self.backend.qpos
        foot = kinematics.foot_position(qpos[:, 1:3])
        return qpos[:, 0] + foot[:, 1] - robot.FOOT_RADIUS

    def close(self) -> None:
        self.backend.close()
