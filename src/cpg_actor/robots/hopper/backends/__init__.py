"""Simulator backends behind one small interface (:class:`Backend`): MuJoCo and PyBullet."""

from __future__ import annotations

from cpg_actor.robots.common.backend import Backend


def make_backend(config, num_robots: int = 1, num_threads: int | None = None) -> Backend:
    """The backend named by ``config.sim`` for ``num_robots`` hoppers (imported on demand)."""
    from cpg_actor.robots.common.actuator import Actuator

    kwargs = dict(
        actuator=Actuator.from_config(config),
        physics_dt=config.physics_dt,
        foot_friction=config.foot_friction,
        num_robots=num_robots,
        num_threads=num_threads,
    )
    if config.sim == "mujoco":
        from cpg_actor.robots.hopper.backends.mujoco_backend import MujocoBackend

        return MujocoBackend(**kwargs)
    if config.sim == "pybullet":
        from cpg_actor.robots.hopper.backends.pybullet_backend import PybulletBackend

        return PybulletBackend(**kwargs)
    if config.sim == "mjx":
        raise ValueError(
            "sim='mjx' steps a batch of robots on JAX's device and has no single-robot backend: "
            "use make_vector_env(num_envs, sim='mjx') "
            "(cpg_actor.robots.hopper.mjx.vector.MjxHopperVectorEnv) "
            "or the id cpg_actor/AnymalHopper-mjx-v0 with gymnasium.make_vec"
        )
    raise ValueError(f"unknown simulator {config.sim!r}; use 'mujoco', 'pybullet' or 'mjx'")


__all__ = ["Backend", "make_backend"]
