"""Shared helpers for the hopper tests: drive a backend directly, one substep at a time."""

from __future__ import annotations

import numpy as np

from cpg_actor.robots.common.actuator import Actuator
from cpg_actor.robots.hopper import description as robot
from cpg_actor.robots.hopper import kinematics
from cpg_actor.robots.hopper.backends import make_backend
from cpg_actor.robots.hopper.config import HopperConfig

SIMS = ("mujoco", "pybullet")
NOMINAL = np.array(robot.NOMINAL_POSE)


def backend_for(sim: str, **overrides):
    config = HopperConfig(sim=sim, **overrides)
    return make_backend(config, num_robots=1), Actuator.from_config(config), config


def place(backend, joint_pos=NOMINAL, hip_height=None) -> None:
    """Robot 0 at rest in ``joint_pos``, foot on the ground unless ``hip_height`` is given."""
    joint_pos = np.asarray(joint_pos, dtype=np.float64)
    if hip_height is None:
        hip_height = float(kinematics.standing_hip_height(joint_pos))
    backend.reset_robots(np.array([0]), np.array([[hip_height, *joint_pos]]), np.zeros((1, 3)))


def simulate(backend, desired_fn, substeps: int, dt: float):
    """Run ``substeps`` physics steps tracking ``desired_fn(t)``; return (qpos, torque) logs."""
    qpos, torque = [], []
    for i in range(substeps):
        desired = np.asarray(desired_fn(i * dt), dtype=np.float64)[None]
        tau = backend.track(desired, 1)
        qpos.append(backend.qpos[0].copy())
        torque.append(tau[0].copy())
    return np.array(qpos), np.array(torque)
