"""The joint actuator, shared by both simulators: PD on the desired position through a DC
motor whose driver saturates at its supply voltage, and a torque limit.

The law, per joint (p_d: desired position, p: measured position, v: measured velocity)::

    tau_pd = Kp (p_d - p) - Kd v                       # the drive's PD controller
    tau_dc = clip(tau_pd, tau_sat (-1 - v / v_max),    # what the motor can deliver at
                          tau_sat ( 1 - v / v_max))    #   speed v (its torque-speed line)
    tau = clip(tau_dc, -tau_max, tau_max)              # the command torque limit

``tau_max`` = 40 N m is the command torque limit of the ANYmal drive. The velocity limit
``v_max`` = 15 rad/s is the no-load speed of a DC motor with stall torque ``tau_sat``: the
torque that pushes *in the direction of motion* falls linearly from ``tau_sat`` at rest to 0
at ``v_max`` (with ``tau_sat`` = 80 N m the full 40 N m is available up to 7.5 rad/s).
Beyond ``v_max`` the back-EMF exceeds the supply voltage and the motor brakes the joint
whatever it is asked; braking torque is never limited below ``tau_max``. Gravity or an
impact can still push a joint past ``v_max``, as on a robot.

``actuator_law="coast"`` (this project's earlier law) instead clips ``tau_sat (1 - v / v_max)``
at 0 from below (and ``tau_sat (-1 - v / v_max)`` at 0 from above): beyond ``v_max`` the drive
gives no torque in the direction of motion but is not made to brake. A real DC motor cannot
do that (its back-EMF then exceeds the supply and drives a braking current); the option keeps
earlier runs reproducible, and is run in numpy at every substep on both simulators.

The ``dc-motor`` law is exactly MuJoCo's ``dcmotor`` actuator with ``input="pos"``, controller gains
``Kp, Kd``, drive voltage limit ``V`` and ``nominal="V tau_sat v_max"`` and ``saturation``
``tau_max`` (no inductance, no friction): the MuJoCo backend runs the law inside the
simulator (:func:`cpg_actor.robots.hopper.mjcf.actuator_xml`), the PyBullet backend calls this
class once per physics substep. ``tests/robots/hopper/test_config_actuator_reward.py`` checks they
agree.

Each constant is one number for every joint, or a tuple: one per joint, or one per joint of a
leg, repeated leg after leg (the Go1's abduction, hip and knee drives differ).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cpg_actor.robots.common.array_namespace import namespace


@dataclass(frozen=True)
class Actuator:
    """Actuator constants; call it on arrays of any matching shape (float64 recommended;
    JAX arrays too, inside ``jax.jit``: the MJX backend runs the law at every substep)."""

    kp: float | tuple[float, ...]
    kd: float | tuple[float, ...]
    torque_limit: float | tuple[float, ...]
    velocity_limit: float | tuple[float, ...]
    saturation_torque: float | tuple[float, ...]
    law: str = "dc-motor"  # or "coast" (module docstring)

    @classmethod
    def from_config(cls, config) -> Actuator:
        return cls(
            kp=constant(config.kp),
            kd=constant(config.kd),
            torque_limit=constant(config.torque_limit),
            velocity_limit=constant(config.velocity_limit),
            saturation_torque=constant(config.saturation_torque),
            law=str(getattr(config, "actuator_law", "dc-motor")),
        )

    def per_joint(self, name: str, num_joints: int) -> np.ndarray:
        """The constant ``name`` for each of ``num_joints`` joints (float64)."""
        value = np.atleast_1d(np.asarray(getattr(self, name), dtype=np.float64))
        if num_joints % value.size:
            raise ValueError(f"Actuator.{name} has {value.size} entries, which do not repeat "
                             f"onto {num_joints} joints")  # fmt: skip
        return np.tile(value, num_joints // value.size)

    def _constants(self, velocity, *names):
        """The constants ``names`` as numbers, or as arrays over ``velocity``'s last axis."""
        if all(isinstance(getattr(self, n), float | int) for n in names):
            return tuple(getattr(self, n) for n in names)
        xp = namespace(velocity)
        n = velocity.shape[-1]
        return tuple(xp.asarray(self.per_joint(name, n), dtype=velocity.dtype) for name in names)

    def torque_bounds(self, velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) torque the drive can produce at joint velocity ``velocity``."""
        # minimum / maximum rather than clip: same result, less of numpy's overhead
        xp = namespace(velocity)
        limit, saturation, speed = self._constants(
            velocity, "torque_limit", "saturation_torque", "velocity_limit"
        )
        drop = velocity * (saturation / speed)
        coast = self.law == "coast"  # never forced to brake: the line is clipped at 0
        floor, ceiling = (0.0, 0.0) if coast else (-limit, limit)
        upper = xp.minimum(xp.maximum(saturation - drop, floor), limit)
        lower = xp.maximum(xp.minimum(-saturation - drop, ceiling), -limit)
        return lower, upper

    def __call__(
        self, desired: np.ndarray, position: np.ndarray, velocity: np.ndarray
    ) -> np.ndarray:
        """Joint torque for desired / measured positions and measured velocities."""
        kp, kd = self._constants(velocity, "kp", "kd")
        torque = kp * (desired - position) - kd * velocity
        lower, upper = self.torque_bounds(velocity)
        xp = namespace(torque)
        return xp.minimum(xp.maximum(torque, lower), upper)


def constant(value) -> float | tuple[float, ...]:
    """A config's actuator constant as :class:`Actuator` holds it: a float, or a tuple of them."""
    if isinstance(value, list | tuple | np.ndarray):
        return tuple(float(v) for v in value)
    return float(value)
