"""The small interface both simulators implement: K hoppers stepped together.

Generalised coordinates, in this order everywhere: ``[hip_height, HFE, KFE]`` (positions,
``qpos``) and ``[hip_velocity, HFE velocity, KFE velocity]`` (``qvel``). A single
environment is a batch of one.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np


class Backend(ABC):
    """K hoppers in one simulator. ``qpos`` / ``qvel`` are (K, 3) float64 arrays kept current
    by updating them in place, so views of them stay valid."""

    name: str = ""
    num_robots: int
    qpos: np.ndarray  # (K, 3): hip height (m), HFE, KFE (rad)
    qvel: np.ndarray  # (K, 3): hip velocity (m/s), HFE, KFE velocity (rad/s)

    @property
    def joint_pos(self) -> np.ndarray:
        return self.qpos[:, 1:3]

    @property
    def joint_vel(self) -> np.ndarray:
        return self.qvel[:, 1:3]

    @property
    def hip_height(self) -> np.ndarray:
        return self.qpos[:, 0]

    @property
    def hip_velocity(self) -> np.ndarray:
        return self.qvel[:, 0]

    @abstractmethod
    def reset_robots(self, index: np.ndarray, qpos: np.ndarray, qvel: np.ndarray) -> None:
        """Put robots ``index`` (k,) in state ``qpos``, ``qvel`` (k, 3), at rest otherwise."""

    @abstractmethod
    def track(
        self, desired: np.ndarray, substeps: int, push: np.ndarray | None = None
    ) -> np.ndarray:
        """``substeps`` physics substeps of all robots, the joint actuators
        (:mod:`cpg_actor.robots.common.actuator`) tracking ``desired`` rad on HFE, KFE: (K, 2)
        at every substep, or (K, substeps, 2), one per substep; returns the joint torque
        applied, mean over the substeps, (K, 2) N m. ``push``: (K,) a vertical force on the
        hip (N, up positive) at every substep (a perturbation's push), or None."""

    def perturb_robots(self, index: np.ndarray, payload: np.ndarray, friction: np.ndarray,
                       strength: np.ndarray) -> None:  # fmt: skip
        """Robots ``index`` (k,) simulated from now on with ``payload`` kg on the hip, foot
        ``friction`` and motor ``strength`` (k,) each (randomised training)."""
        raise NotImplementedError(f"the {self.name} backend has no per-robot perturbations")

    @abstractmethod
    def unstable(self) -> np.ndarray:
        """(K,) bool: robots the simulator found unstable since their last reset."""

    @abstractmethod
    def foot_state(self) -> tuple[np.ndarray, np.ndarray]:
        """World position and velocity (K, 3) of the foot sphere centre, read from the simulator."""

    @abstractmethod
    def contact(self) -> np.ndarray:
        """(K,) bool: the foot touches the ground."""

    @abstractmethod
    def total_mass(self) -> float:
        """Mass of one robot's moving links, kg, as the simulator loaded it (a payload
        included)."""

    @abstractmethod
    def render(self, index: int, width: int, height: int) -> np.ndarray:
        """An RGB image (height, width, 3) uint8 of robot ``index``, side view."""

    def get_state(self) -> np.ndarray:
        """Everything needed to continue the simulation, ``(K, S)`` float64 (a copy).

        This default is ``[qpos, qvel]``, which :meth:`set_state` restores with
        :meth:`reset_robots`: exact for the state itself, but a simulator's internal caches
        (e.g. contact warm starts) start afresh. Backends that can do better override both."""
        return np.concatenate([self.qpos, self.qvel], axis=1)

    def set_state(self, state: np.ndarray) -> None:
        """Restore what :meth:`get_state` returned."""
        state = np.asarray(state, dtype=np.float64)
        expected = (self.num_robots, self.qpos.shape[1] + self.qvel.shape[1])
        if state.shape != expected:
            raise ValueError(f"a {self.name} state must have shape {expected}, got {state.shape}")
        nq = self.qpos.shape[1]
        self.reset_robots(np.arange(self.num_robots), state[:, :nq], state[:, nq:])

    def close(self) -> None:  # noqa: B027 - optional
        """Release simulator resources."""
