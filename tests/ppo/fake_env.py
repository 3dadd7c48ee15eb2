"""A tiny, fast stand-in for the hopper vector env with the same contract (tests only).

Joints follow the desired positions with first-order lag; the "hip" rises with the knee
speed. Episodes end by time limit (truncated) or, at random, by a fall (terminated).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from gymnasium import spaces

from cpg_actor.robots.hopper.plugin import ROBOT as HOPPER
from cpg_actor.robots.plugin import Robot
from cpg_actor.robots.registry import ROBOTS, register_robot
from cpg_actor.robots.spec import RobotSpec


@dataclass
class FakeConfig:
    control_dt: float = 0.01
    episode_steps: int = 15
    fall_probability: float = 0.02
    sim: str = "fake"


class FakeHopperVectorEnv:
    def __init__(self, num_envs: int, config: FakeConfig | None = None, num_threads=None) -> None:
        self.num_envs = num_envs
        self.config = config or FakeConfig()
        self.single_action_space = spaces.Box(
            np.array([-1.0, -2.5], dtype=np.float32), np.array([1.5, 0.0], dtype=np.float32)
        )
        self.single_observation_space = spaces.Box(-np.inf, np.inf, (8,), np.float32)
        # the hopper's joints, so that the hopper's agents build on it
        self.robot = RobotSpec(
            name="fake-hopper",
            joint_names=("HFE", "KFE"),
            nominal_pose=(0.4, -0.8),
            action_low=(-1.0, -2.5),
            action_high=(1.5, 0.0),
            control_dt=self.config.control_dt,
            observation_names=tuple(f"o{i}" for i in range(8)),
        )
        self.rng = np.random.default_rng(0)
        self.nan_at_step: int | None = None  # inject a NaN reward at this global step
        self.interrupt_at_step: int | None = None  # raise KeyboardInterrupt here (a kill)
        self.global_step = 0

    def _reset_rows(self, rows: np.ndarray) -> None:
        k = int(rows.sum()) if rows.dtype == bool else len(rows)
        self.q[rows] = np.array([0.4, -0.8]) + 0.05 * self.rng.standard_normal((k, 2))
        self.qd[rows] = 0.0
        self.pd[rows] = np.array([0.4, -0.8])
        self.h[rows] = 0.5
        self.hv[rows] = 0.0
        self.t[rows] = 0

    def _obs(self) -> np.ndarray:
        h = self.h[:, None]
        return np.concatenate([self.q, self.qd, self.pd, h, self.hv[:, None]], axis=1).astype(
            np.float32
        )

    def reset(self, seed: int | None = None):
        if seed is not None:
            self.rng = np.random.default_rng(seed)
        n = self.num_envs
        self.q, self.qd, self.pd = np.zeros((n, 2)), np.zeros((n, 2)), np.zeros((n, 2))
        self.h, self.hv, self.t = np.zeros(n), np.zeros(n), np.zeros(n, dtype=np.int64)
        self._reset_rows(np.ones(n, dtype=bool))
        return self._obs(), {}

    def step(self, actions: np.ndarray):
        actions = np.asarray(actions, dtype=np.float64)
        assert actions.shape == (self.num_envs, 2)
        if self.interrupt_at_step is not None and self.global_step >= self.interrupt_at_step:
            raise KeyboardInterrupt
        old = self.q.copy()
        self.q = self.q + 0.3 * (actions - self.q)
        self.qd = (self.q - old) / self.config.control_dt
        self.pd = actions
        self.hv = 0.1 * np.abs(self.qd[:, 1])
        self.h = 0.5 + 0.5 * (self.h - 0.5) + 0.01 * self.hv
        self.t += 1
        r1 = self.hv**2
        r2 = -0.1 * ((actions - self.q) ** 2).sum(1)
        reward = (r1 + r2).astype(np.float32)
        self.global_step += 1
        if self.nan_at_step is not None and self.global_step >= self.nan_at_step:
            reward[:] = np.nan
        terminated = self.rng.random(self.num_envs) < self.config.fall_probability
        truncated = self.t >= self.config.episode_steps
        info = {
            "reward_terms": {"r1": r1, "r2": r2},
            "hip_height": self.h.copy(),
            "foot_height": self.h - 0.45,
            "joint_torque": 10 * (actions - self.q),
        }
        done = terminated | truncated
        info["episode_metrics"] = {"hop_height": np.where(done, self.h - 0.5, np.nan)}
        obs = self._obs()
        if done.any():
            info["final_obs"] = obs.copy()
            self._reset_rows(done)
            obs = self._obs()
        return obs, reward, terminated, truncated, info

    def get_state(self) -> dict:
        import torch

        arrays = {
            k: torch.from_numpy(getattr(self, k).copy()) for k in ("q", "qd", "pd", "h", "hv", "t")
        }
        return {"arrays": arrays, "rng": self.rng.bit_generator.state}

    def set_state(self, state: dict) -> None:
        for key, value in state["arrays"].items():
            setattr(self, key, value.numpy().copy())
        self.rng = np.random.default_rng(0)
        self.rng.bit_generator.state = state["rng"]

    def close(self) -> None:
        pass


def fake_runner(agent: str = "mlp", **ppo):
    """A started ``Runner`` of ``agent`` on 4 fake envs: rollouts of 16 steps, 3 epochs of 2
    minibatches, unless ``ppo`` (any ``PPOConfig`` field) says otherwise."""
    from cpg_actor.config import TrainConfig
    from cpg_actor.ppo import PPOConfig
    from cpg_actor.training.runner import Runner

    settings = {"num_steps": 16, "num_epochs": 3, "num_minibatches": 2, **ppo}
    config = TrainConfig(
        agent=agent,
        num_envs=4,
        total_steps=4 * settings["num_steps"] * 10,
        ppo=PPOConfig(**settings),
        env=FakeConfig(),
        eval_interval=0,
    )
    runner = Runner(config, env=FakeHopperVectorEnv(4, config.env), tensorboard=False)
    runner.start_episodes()
    return runner


def fake_robot(name: str = "fake-hopper", make: Callable[..., Any] | None = None) -> Robot:
    """The stand-in env as a robot (``--robot NAME`` once registered): the hopper's entry
    (its CPG layouts, start gait, metrics) on :class:`FakeHopperVectorEnv`, or on ``make``'s
    envs (``make(num_envs, config, num_threads)``)."""
    return replace(HOPPER, name=name, model=name, config_class=FakeConfig,
                   make=make or FakeHopperVectorEnv, gym_ids=(), simulators=("fake",),
                   agent_defaults={})  # fmt: skip


class registered:
    """``with registered(robot):`` the robot is in the registry, and only inside."""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot

    def __enter__(self) -> Robot:
        return register_robot(self.robot)

    def __exit__(self, *exc: object) -> None:
        ROBOTS.pop(self.robot.name, None)
