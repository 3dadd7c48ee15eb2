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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cpg_actor.robots.common.array_namespace import namespace


@dataclass(frozen=True)
class Actuator:
    """Actuator constants; call it on arrays of any matching shape (float64 recommended;
    JAX arrays too, inside ``jax.jit``: the MJX backend runs the law at every substep)."""

    kp: float
    kd: float
    torque_limit: float
    velocity_limit: float
    saturation_torque: float
    law: str = "dc-motor"  # or "coast" (module docstring)

    @classmethod
    def from_config(cls, config) -> Actuator:
        return cls(
            kp=float(config.kp),
            kd=float(config.kd),
            torque_limit=float(config.torque_limit),
            velocity_limit=float(config.velocity_limit),
            saturation_torque=float(config.saturation_torque),
            law=str(getattr(config, "actuator_law", "dc-motor")),
        )

    def torque_bounds(self, velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) torque the drive can produce at joint velocity ``velocity``."""
        # minimum / maximum rather than clip: same result, less of numpy's overhead
        xp = namespace(velocity)
        limit, drop = self.torque_limit, velocity * (self.saturation_torque / self.velocity_limit)
        coast = self.law == "coast"  # never forced to brake: the line is clipped at 0
        floor, ceiling = (0.0, 0.0) if coast else (-limit, limit)
        upper = xp.minimum(xp.maximum(self.saturation_torque - drop, floor), limit)
        lower = xp.maximum(xp.minimum(-self.saturation_torque - drop, ceiling), -limit)
        return lower, upper

    def __call__(
        self, desired: np.ndarray, position: np.ndarray, velocity: np.ndarray
    ) -> np.ndarray:
        """Joint torque for desired / measured positions and measured velocities."""
        torque = self.kp * (desired - position) - self.kd * velocity
        lower, upper = self.torque_bounds(velocity)
        xp = namespace(torque)
        return xp.minimum(xp.maximum(torque, lower), upper)
