"""`QuadrupedModel`: what the quadruped envs need to know about one robot, in one place.

A robot's folder builds one from its description and MJCF generator
(:meth:`QuadrupedModel.from_description`); the MuJoCo env, the MJX env and the single-robot env
read everything robot-specific from it. The MJCF must have a
free-jointed base body, the 12 hinge joints in ``joint_names`` order each with an actuator of
the same name, a site ``<leg>_foot`` at each foot centre, and (for the MuJoCo env) the sensors
of :data:`SENSORS` after the 12 ``actuatorfrc`` ones: ``gyro`` and ``velocimeter`` on a site
``imu`` of the base, a ``framepos`` per foot site, and a ``touch`` sensor over the base (its
contacts with the ground end an episode).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any

import numpy as np

from cpg_actor.tasks import velocity as task

# after the 12 actuatorfrc sensors (N m), in this order (the env reads them by these offsets)
SENSORS = (("gyro", 3), ("velocimeter", 3), ("feet", 12), ("base_touch", 1))


@dataclass(frozen=True)
class QuadrupedModel:
    """One quadruped as the envs see it (module docstring)."""

    name: str  # the RobotSpec name (the exported policy's robot_model)
    state_key: str  # the key of the MuJoCo env's get_state() ("mjx-" + it: the MJX env's)
    config_class: type  # its QuadrupedConfig (sub)class
    legs: tuple[str, ...]  # the feet, in joint order (columns of info["contact"])
    joint_names: tuple[str, ...]  # the 12 actuated joints, in action order
    nominal_pose: tuple[float, ...]  # rad
    joint_limits: dict[str, tuple[float, float]]  # rad, also the action bounds
    foot_radius: float  # m, the contact sphere's
    total_mass: float  # kg (the cost of transport's weight)
    gravity: float  # m/s^2
    base_body: str  # the free body's name
    # the MJX env's stand-in for the touch sensor: a box fixed to the base (centre, half
    # sizes, m, in the base frame) whose corners at or below the ground are a fall
    base_box: tuple[tuple[float, float, float], tuple[float, float, float]]
    # (actuator, torque_control) -> the MJCF text (actuator: the law's constants,
    # torque_control: plain motors and no sensors, for MJX)
    mjcf_text: Callable[..., str]
    # render_frame's camera: it follows the base's subtree centre of mass
    camera: dict[str, float] = field(
        default_factory=lambda: {"distance": 2.5, "azimuth": 120.0, "elevation": -20.0}
    )

    @classmethod
    def from_description(cls, description: ModuleType, **fields: Any) -> QuadrupedModel:
        """The model of the robot whose ``description`` module names its facts as every
        quadruped's does: ``LEGS``, ``JOINT_NAMES``, ``NOMINAL_POSE``, ``ACTION_LIMITS`` (the
        ``joint_limits``), ``FOOT_RADIUS``, ``TOTAL_MASS``, ``GRAVITY`` and ``BASE_BOX``;
        ``fields``: the other fields."""
        return cls(
            legs=description.LEGS,
            joint_names=description.JOINT_NAMES,
            nominal_pose=description.NOMINAL_POSE,
            joint_limits=description.ACTION_LIMITS,
            foot_radius=description.FOOT_RADIUS,
            total_mass=description.TOTAL_MASS,
            gravity=description.GRAVITY,
            base_box=description.BASE_BOX,
            **fields,
        )

    @property
    def low(self) -> np.ndarray:
        return np.array([self.joint_limits[j][0] for j in self.joint_names])

    @property
    def high(self) -> np.ndarray:
        return np.array([self.joint_limits[j][1] for j in self.joint_names])

    @property
    def observation_names(self) -> tuple[str, ...]:
        return task.observation_names(self.joint_names)  # the velocity task's, 45 entries

    def observation_sources(self, lin_vel: bool = False) -> tuple[dict[str, Any], ...]:
        """Where the actor's observation entries come from (``lin_vel``: the env's
        ``observe_lin_vel``)."""
        return task.observation_sources(self.nominal_pose, lin_vel)
