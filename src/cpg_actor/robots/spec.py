"""`RobotSpec`: what an environment tells the agents about the robot it simulates, defined once
by the environment (from the robot's description) and read by everything else.

Agents are built from it (the number of joints, the nominal pose the actions are centred on,
the control period of the CPG) and, for the CPG agents, from the robot's registry entry (its
CPG layouts and start gait, :class:`cpg_actor.robots.plugin.Robot`), so a new robot is a new
environment, not a change to the trainer.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np


class EnvConfig(Protocol):
    """What the trainer reads of every robot's env config (``TrainConfig.env``, an instance
    of its ``Robot.config_class``): the control period and the length of an episode, each read
    as this attribute and nowhere guessed. A config class may give more, each used where it
    is there: ``from_dict(values)`` (``--set env.KEY=...``), ``replace(**changes)``, ``sim``
    (a robot on several simulators), ``perturbation`` and ``randomize``
    (``docs/robustness.md``)."""

    @property
    def control_dt(self) -> float:
        """Seconds of one control step (one env step)."""
        ...

    @property
    def episode_steps(self) -> int:
        """Control steps of an episode, after which it is truncated."""
        ...


@dataclass(frozen=True)
class RobotSpec:
    """The robot behind an environment's joint-position actions."""

    name: str  # the robot model, e.g. "anymal-hopper" (Robot.model; an exported policy's)
    joint_names: tuple[str, ...]  # actuated joints, in action order
    nominal_pose: tuple[float, ...]  # rad, the standing pose actions are centred on
    action_low: tuple[float, ...]  # rad, joint limits (the action space)
    action_high: tuple[float, ...]
    control_dt: float  # s, one control step (one env step)
    observation_names: tuple[str, ...]
    # the observation (one of observation_names) that sets the CPG's drive d (paper eq. 3:
    # nu(d), rho(d)), as it comes from the env, before normalisation: the quadruped's
    # forward-speed command. None: no drive (the hopper: d = 0)
    drive_observation: str | None = None
    # the velocity command's observations (forward, lateral m/s, yaw rate rad/s), which a
    # planar drive reads (agent_config.cpg_planar_steps); empty: the robot takes no such command
    command_observations: tuple[str, ...] = ()
    # observations evaluation records as traces of their own, by name (the hopper's
    # hip_height), with their value after reset as standing_<name>
    traced_observations: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        n = len(self.joint_names)
        for name in ("nominal_pose", "action_low", "action_high"):
            if len(getattr(self, name)) != n:
                raise ValueError(f"RobotSpec.{name} needs {n} entries, one per joint")
        low, high, pose = (np.asarray(v) for v in (self.action_low, self.action_high,
                                                    self.nominal_pose))  # fmt: skip
        if not (np.all(low < high) and np.all(low <= pose) and np.all(pose <= high)):
            raise ValueError(
                "RobotSpec needs action_low < action_high and the nominal pose between"
            )
        if not self.control_dt > 0:
            raise ValueError(f"RobotSpec.control_dt must be > 0, got {self.control_dt!r}")
        if self.drive_observation is not None and (
            self.drive_observation not in self.observation_names
        ):
            raise ValueError(
                f"RobotSpec.drive_observation {self.drive_observation!r} is not one of the "
                f"observation names {self.observation_names}"
            )
        missing = set(self.command_observations) - set(self.observation_names)
        if missing:
            raise ValueError(f"RobotSpec.command_observations {sorted(missing)} are not observed")
        unknown = set(self.traced_observations) - set(self.observation_names)
        if unknown:
            raise ValueError(f"RobotSpec.traced_observations {sorted(unknown)} are not observed")

    @property
    def num_joints(self) -> int:
        return len(self.joint_names)

    @property
    def drive_index(self) -> int | None:
        """The drive observation's index in the observation vector (None: no drive)."""
        if self.drive_observation is None:
            return None
        return self.observation_names.index(self.drive_observation)
