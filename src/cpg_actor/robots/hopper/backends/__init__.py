"""Simulator backends of the hopper behind one small interface (:class:`Backend`).

A backend is a file here with a :class:`Backend` subclass, and a line in :data:`BACKENDS`:
``HopperConfig.sim`` (``--sim``) then accepts its name, and
:class:`~cpg_actor.robots.hopper.simulation.HopperSimulation` gives it the observation, the
reward, the termination and the resets. The MJX simulator steps the whole batch on JAX's
device instead (:mod:`cpg_actor.robots.hopper.mjx`) and has no backend here.
"""

from __future__ import annotations

import importlib

from cpg_actor.robots.common.backend import Backend

# HopperConfig.sim -> its backend, "module:Class" (imported when asked for)
BACKENDS = {
    "mujoco": "cpg_actor.robots.hopper.backends.mujoco_backend:MujocoBackend",
    "pybullet": "cpg_actor.robots.hopper.backends.pybullet_backend:PybulletBackend",
}
BATCHED_ONLY = "mjx"  # the simulator with no single-robot backend


def make_backend(config, num_robots: int = 1, num_threads: int | None = None) -> Backend:
    """The backend named by ``config.sim`` for ``num_robots`` hoppers (imported on demand),
    built as every backend is: ``(actuator, physics_dt, foot_friction, num_robots,
    num_threads, payload)``, the config's perturbation in the actuator (motor strength), the
    foot friction and the payload."""
    from cpg_actor.robots.common.actuator import Actuator

    if config.sim == BATCHED_ONLY:
        raise ValueError(
            "sim='mjx' steps a batch of robots on JAX's device and has no single-robot backend: "
            "use make_vector_env(num_envs, sim='mjx') "
            "(cpg_actor.robots.hopper.mjx.vector.MjxHopperVectorEnv) "
            "or the id cpg_actor/AnymalHopper-mjx-v0 with gymnasium.make_vec"
        )
    if config.sim not in BACKENDS:
        raise ValueError(
            f"unknown simulator {config.sim!r}; use {', '.join(map(repr, BACKENDS))} or 'mjx'"
        )
    module, name = BACKENDS[config.sim].split(":")
    backend = getattr(importlib.import_module(module), name)
    perturbation = config.perturbation
    return backend(
        actuator=perturbation.actuator(Actuator.from_config(config)),
        physics_dt=config.physics_dt,
        foot_friction=perturbation.ground_friction(config.foot_friction),
        num_robots=num_robots,
        num_threads=num_threads,
        payload=perturbation.payload,
    )


__all__ = ["BACKENDS", "Backend", "make_backend"]
