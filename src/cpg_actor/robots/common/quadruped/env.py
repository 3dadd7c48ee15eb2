"""`QuadrupedEnv`: one quadruped as a Gymnasium ``Env`` (e.g. ``cpg_actor/AnymalB-v0`` with
``gymnasium.make``), for Stable-Baselines3, CleanRL-style scripts and Gymnasium's checkers. A
robot's env is a subclass naming its MuJoCo vector env (``vector_env``).

It is the robot's :class:`~cpg_actor.robots.common.quadruped.vector.QuadrupedVectorEnv` with
one robot: the same
observation (45, float32), action (12 desired joint positions, rad, or [-1, 1] with
``normalized_actions``), reward, episode ends and reset distribution, from the same code.
``info`` is the vector env's for one robot, without ``final_obs`` (an episode's last step
returns its last observation, as a single env does) and with ``episode_metrics`` on an
episode's last step only.

Seeding: ``reset(seed=s)`` seeds :attr:`np_random`, and every random draw of the env (joint
noise, commands) comes from it, so env 0 of the vector env reset with ``seed=s`` and this env
reset with ``seed=s`` follow the same trajectory under the same actions, later episodes
included (``reset()`` without a seed after an episode ends starts the episode the vector env's
autoreset would).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import gymnasium as gym
import numpy as np

from cpg_actor.robots.common.checks import check_render_mode
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.common.quadruped.vector import QuadrupedVectorEnv, resolve_config


def config_with(
    config: QuadrupedConfig | dict | None,
    overrides: dict[str, Any],
    config_class: type = QuadrupedConfig,
) -> QuadrupedConfig:
    """``config`` (or the defaults of ``config_class``) with keyword overrides applied,
    validated. A partial ``reward_scales`` changes those terms and keeps the others."""
    config = resolve_config(config, config_class)
    fields = [f.name for f in dataclasses.fields(config_class)]
    unknown = set(overrides) - set(fields)
    if unknown:
        raise ValueError(
            f"unknown {config_class.__name__} fields {sorted(unknown)}; accepted: {sorted(fields)}"
        )
    changes = dict(overrides)
    if isinstance(changes.get("reward_scales"), dict):
        changes["reward_scales"] = {**config.reward_scales, **changes["reward_scales"]}
    return config.replace(**changes)


def one_robot(value: Any) -> Any:
    """The first row of a vector env's ``info`` entry: a Python scalar for per-env numbers,
    an array for per-env vectors, dicts entry by entry."""
    if isinstance(value, dict):
        return {name: one_robot(entry) for name, entry in value.items()}
    value = np.asarray(value)
    return value[0].item() if value.ndim == 1 else value[0].copy()


class QuadrupedEnv(gym.Env):
    """One quadruped walking on flat ground (module docstring).

    Args:
        config: the robot's config (or a dict of its fields); defaults if None.
        render_mode: None or ``"rgb_array"`` (MuJoCo's offscreen renderer: needs OpenGL).
        **overrides: any field of the robot's config, e.g. ``normalized_actions=True``.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 50}
    vector_env: type[QuadrupedVectorEnv]  # the robot's MuJoCo env (a subclass sets it)
    mjx_env_id: str = ""  # the robot's batched MJX Gymnasium id, named in an error

    def __init__(
        self,
        config: QuadrupedConfig | dict | None = None,
        render_mode: str | None = None,
        **overrides: Any,
    ) -> None:
        quadruped = self.vector_env.quadruped
        self.config = config_with(config, overrides, quadruped.config_class)
        if self.config.sim != "mujoco":
            raise ValueError(
                f"the single-robot quadruped env runs on MuJoCo (sim='mujoco'), got "
                f"sim={self.config.sim!r}; MJX is batched only: "
                f"gymnasium.make_vec('{self.mjx_env_id}', num_envs=N)"
            )
        check_render_mode(render_mode, self.metadata)
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.config.control_dt)}
        self._vec = self.vector_env(1, self.config, num_threads=1)
        self.observation_space = self._vec.single_observation_space
        self.action_space = self._vec.single_action_space
        self.robot = self._vec.robot  # what the agents are built from
        self._needs_reset = True
        # the first observation of the episode the vector env's autoreset started when the
        # last one ended: reset() without a seed continues with it
        self._next_obs: np.ndarray | None = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """A new episode; ``seed`` seeds :attr:`np_random`. ``options`` is not used."""
        self._check_open("reset")
        super().reset(seed=seed)
        rng = self.np_random  # made from a random seed on the first reset without one
        rngs = self._vec.env_rngs
        if seed is None and self._next_obs is not None and rngs is not None and rngs[0] is rng:
            obs, command = self._next_obs, self._vec.command[0].copy()
        else:
            self._vec.env_rngs = [rng]
            if seed is not None or not self._vec.draws.rngs:  # a perturbation's own generator
                self._vec.draws.seed([seed])
            batch, info = self._vec.reset()  # draws from rng
            obs, command = batch[0], info["command"][0]
        self._next_obs = None
        self._needs_reset = False
        return obs, {"command": command}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        self._check_open("step")
        shape = self.action_space.shape
        try:
            array = np.asarray(action, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(
                f"action must be {shape[0]} numbers (desired joint positions), got {action!r}"
            ) from None
        if array.shape != shape:
            raise ValueError(
                f"action must have shape {shape} (desired joint positions, rad, joints "
                f"{', '.join(self.robot.joint_names)}), got {array.shape}"
            )
        if self._needs_reset:
            raise gym.error.ResetNeeded("call reset() before step() (and after an episode ends)")
        obs, reward, terminated, truncated, info = self._vec.step(array[None])
        ended = bool(terminated[0] or truncated[0])
        if ended:  # the vector env has started the next episode already
            self._next_obs = obs[0]
            self._needs_reset = True
            obs = info["final_obs"]
        # episode_metrics only where the episode ended (the vector env's rows are NaN elsewhere)
        skip = {"final_obs", "_final_obs"} | (set() if ended else {"episode_metrics"})
        info = {k: one_robot(v) for k, v in info.items() if k not in skip}
        return obs[0], float(reward[0]), bool(terminated[0]), bool(truncated[0]), info

    def render(self) -> np.ndarray | None:
        """An RGB frame ``(H, W, 3)`` uint8, the camera following the base
        (``QuadrupedVectorEnv.render_frame``); after an episode's last step, the next episode's
        start."""
        if self.render_mode is None:
            gym.logger.warn("render() called without render_mode; pass render_mode='rgb_array'")
            return None
        self._check_open("render")
        return self._vec.render_frame(0)

    def close(self) -> None:
        if getattr(self, "_vec", None) is not None:
            self._vec.close()
            self._vec = None

    def _check_open(self, what: str) -> None:
        if getattr(self, "_vec", None) is None:
            raise gym.error.ClosedEnvironmentError(
                f"{what}() on a closed environment; make a new one"
            )
