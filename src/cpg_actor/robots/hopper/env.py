"""`HopperEnv`: the paper's test bed, one ANYmal leg hopping on a vertical rail (Gymnasium 1.x).

Action: desired joint positions ``[HFE, KFE]`` in rad (float32 Box bounded by the joint limits;
finite values outside are clipped to it). Observation: float32 (8,) in the order of
:data:`OBS_NAMES`, not normalised. Reward: paper eq. 4 (:mod:`cpg_actor.robots.hopper.reward`).
Episodes are truncated after ``episode_steps`` control steps; ``terminated`` only reports a
simulation blow-up. See ``docs/hopper.md``.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector.utils import batch_space

from cpg_actor.robots.common.checks import check_render_mode, real_actions
from cpg_actor.robots.hopper import description as robot
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.simulation import HopperSimulation, StepResult
from cpg_actor.robots.hopper.task import (
    ACTION_HIGH,
    ACTION_LOW,
    NOMINAL_POSE,
    OBS_BOUND,
    OBS_NAMES,
    desired_positions,
)
from cpg_actor.robots.spec import RobotSpec


def resolve_config(
    config: HopperConfig | dict | None, sim: str | None, overrides: dict[str, Any]
) -> HopperConfig:
    """``config`` (or the defaults) with ``sim`` and keyword overrides applied, validated."""
    if config is None:
        config = HopperConfig()
    elif isinstance(config, dict):
        config = HopperConfig.from_dict(config)
    elif not isinstance(config, HopperConfig):
        raise ValueError(f"config must be a HopperConfig or a dict, got {type(config).__name__}")
    changes = dict(overrides)
    if sim is not None:
        changes["sim"] = sim
    return config.replace(**changes) if changes else config.replace()


def init_vector_env(
    env: Any,
    num_envs: Any,
    config: HopperConfig | dict | None,
    sim: str | None,
    max_episode_steps: int | None,
    overrides: dict[str, Any],
) -> None:
    """What every hopper vector env (MuJoCo / PyBullet, MJX) sets up alike: the validated
    ``config``, ``num_envs``, the single and batched spaces, the ``robot`` the agents are built
    from and the render rate. ``max_episode_steps`` is what ``gymnasium.make_vec`` passes from
    the registered spec: it must equal ``episode_steps`` (the env truncates its episodes)."""
    if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
        raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
    env.config = resolve_config(config, sim, overrides)
    if max_episode_steps is not None and max_episode_steps != env.config.episode_steps:
        raise ValueError(
            f"max_episode_steps={max_episode_steps} differs from episode_steps="
            f"{env.config.episode_steps}; give both the same value"
        )
    env.num_envs = int(num_envs)
    env.single_observation_space = observation_space()
    env.single_action_space = action_space(env.config.normalized_actions)
    env.robot = robot_spec(env.config)  # what the agents are built from
    env.observation_space = batch_space(env.single_observation_space, env.num_envs)
    env.action_space = batch_space(env.single_action_space, env.num_envs)
    env.metadata = {**env.metadata, "render_fps": round(1.0 / env.config.control_dt)}


def robot_spec(config: HopperConfig) -> RobotSpec:
    """The hopper as the agents see it (joints, nominal pose, limits from the description)."""
    return RobotSpec(
        name="anymal-hopper",
        joint_names=tuple(robot.JOINT_NAMES),
        nominal_pose=tuple(float(v) for v in NOMINAL_POSE),
        action_low=tuple(float(v) for v in ACTION_LOW),
        action_high=tuple(float(v) for v in ACTION_HIGH),
        control_dt=float(config.control_dt),
        observation_names=tuple(OBS_NAMES),
        traced_observations=("hip_height",),  # the hop, drawn in eval's traces
    )


def action_space(normalized: bool = False) -> spaces.Box:
    """Desired [HFE, KFE] positions in rad within the joint limits, or [-1, 1] per joint."""
    if normalized:
        return spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
    return spaces.Box(
        low=ACTION_LOW.astype(np.float32), high=ACTION_HIGH.astype(np.float32), dtype=np.float32
    )


def observation_space() -> spaces.Box:
    """Unbounded in principle; every observation is clipped to +-1e6 (only a blown-up
    simulation gets there), which keeps the bounds finite."""
    return spaces.Box(low=-OBS_BOUND, high=OBS_BOUND, shape=(len(OBS_NAMES),), dtype=np.float32)


def check_actions(actions: Any, shape: tuple[int, ...], normalized: bool = False) -> np.ndarray:
    """Desired positions (rad, float64) clipped to the joint limits; ValueError on a bad shape
    or NaN/inf. ``normalized``: the actions are in [-1, 1], -1 the lower and +1 the upper joint
    limit (clipped to [-1, 1] first)."""
    array = real_actions(actions, f"of shape {shape}")
    if array.shape != shape:
        raise ValueError(
            f"actions must have shape {shape} (desired [HFE, KFE] positions, rad), "
            f"got {array.shape}"
        )
    if not np.isfinite(array).all():
        raise ValueError(f"actions must be finite, got {array.tolist()}")
    return desired_positions(array, normalized)


def step_info(result: StepResult, row: int) -> dict[str, Any]:
    return {
        "reward_terms": {k: float(v[row]) for k, v in result.reward_terms.items()},
        "hip_height": float(result.hip_height[row]),
        "foot_height": float(result.foot_height[row]),
        "joint_torque": result.joint_torque[row].copy(),
        "desired_position": result.desired_position[row].copy(),
        "measured_position": result.measured_position[row].copy(),
        "measured_velocity": result.measured_velocity[row].copy(),
        "foot_position": result.foot_position[row].copy(),
    }


class HopperEnv(gym.Env):
    """One ANYmal leg on a vertical rail (paper section IV); ``cpg_actor/AnymalHopper-v0``.

    Args:
        config: a :class:`HopperConfig` (or a dict of its keys); defaults if None.
        render_mode: None or ``"rgb_array"``.
        sim: ``"mujoco"`` or ``"pybullet"``, overrides ``config.sim``.
        **overrides: any :class:`HopperConfig` field, e.g. ``kp=100.0``.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 100}

    def __init__(
        self,
        config: HopperConfig | dict | None = None,
        render_mode: str | None = None,
        sim: str | None = None,
        **overrides: Any,
    ) -> None:
        self.config = resolve_config(config, sim, overrides)
        check_render_mode(render_mode, self.metadata)
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.config.control_dt)}
        self.action_space = action_space(self.config.normalized_actions)
        self.observation_space = observation_space()
        self.robot = robot_spec(self.config)
        self.sim = HopperSimulation(self.config, num_robots=1, num_threads=1)
        self._needs_reset = True

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        if getattr(self, "sim", None) is None:
            raise gym.error.ClosedEnvironmentError(
                "reset() on a closed environment; make a new one"
            )
        super().reset(seed=seed)
        if seed is not None or not self.sim.draws.rngs:
            self.sim.seed_perturbations([seed])
        self.sim.reset_robots(np.array([0]), self.sim.sample_noise(self.np_random)[None])
        self._needs_reset = False
        measured = self.sim.backend.joint_pos[0].copy()
        info = {
            "hip_height": float(self.sim.backend.hip_height[0]),
            "foot_height": float(self.sim.foot_height()[0]),
            "desired_position": NOMINAL_POSE.copy(),
            "measured_position": measured,
        }
        return self.sim.observation()[0], info

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if getattr(self, "sim", None) is None:
            raise gym.error.ClosedEnvironmentError("step() on a closed environment; make a new one")
        desired = check_actions(action, (2,), self.config.normalized_actions)
        if self._needs_reset:
            raise gym.error.ResetNeeded(
                "call reset() before step() (and after an episode terminated)"
            )
        result = self.sim.step(desired[None])
        terminated = bool(result.terminated[0])
        self._needs_reset = terminated
        return (
            result.obs[0],
            float(result.reward[0]),
            terminated,
            bool(result.truncated[0]),
            step_info(result, 0),
        )

    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn("render() called without render_mode; pass render_mode='rgb_array'")
            return None
        return self.sim.backend.render(0, self.config.render_width, self.config.render_height)

    def close(self) -> None:
        if getattr(self, "sim", None) is not None:
            self.sim.close()
            self.sim = None
