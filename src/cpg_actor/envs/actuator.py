"""The joint actuator, shared by both simulators: PD on the desired position, torque-limited and
velocity-limited, evaluated in numpy once per physics substep and applied as a joint torque.

The law, per joint (p_d: desired position, p: measured position, v: measured velocity)::

    tau_pd = Kp (p_d - p) - Kd v
    tau_hi(v) = clip(tau_sat (1 - v / v_max), 0, tau_max)
    tau_lo(v) = clip(tau_sat (-1 - v / v_max), -tau_max, 0)
    tau = min(max(tau_pd, tau_lo(v)), tau_hi(v))

``tau_max`` = 40 N m is the command torque limit of the ANYmal drive. The velocity limit
``v_max`` = 15 rad/s is modelled by the torque-speed line of a DC motor with stall torque
``tau_sat``: the torque that pushes *in the direction of motion* falls linearly from
``tau_sat`` at rest to 0 at ``v_max`` (with ``tau_sat`` = 80 N m the full 40 N m is available
up to 7.5 rad/s). Beyond ``v_max`` the drive can only brake; braking torque is never limited
below ``tau_max``. Gravity or an impact can still push a joint past ``v_max``, as on a robot.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Actuator:
    """Actuator constants; call it on arrays of any matching shape (float64 recommended)."""

    kp: float
    kd: float
    torque_limit: float
    velocity_limit: float
    saturation_torque: float

    @classmethod
    def from_config(cls, config) -> Actuator:
        return cls(
            kp=float(config.kp),
            kd=float(config.kd),
            torque_limit=float(config.torque_limit),
            velocity_limit=float(config.velocity_limit),
            saturation_torque=float(config.saturation_torque),
        )

    def torque_bounds(self, velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) torque the drive can produce at joint velocity ``velocity``."""
        # np.minimum / np.maximum rather than np.clip: same result, a third of the overhead
        drop = velocity * (self.saturation_torque / self.velocity_limit)
        upper = np.minimum(np.maximum(self.saturation_torque - drop, 0.0), self.torque_limit)
        lower = np.maximum(np.minimum(-self.saturation_torque - drop, 0.0), -self.torque_limit)
        return lower, upper

    def __call__(
        self, desired: np.ndarray, position: np.ndarray, velocity: np.ndarray
    ) -> np.ndarray:
        """Joint torque for desired / measured positions and measured velocities."""
        torque = self.kp * (desired - position) - self.kd * velocity
        lower, upper = self.torque_bounds(velocity)
        return np.minimum(np.maximum(torque, lower), upper)
