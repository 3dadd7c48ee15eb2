"""The reference hopping CPG parameters that warm-start the Cho et al. 2019 baseline.

The paper warm-starts Cho et al.'s policy toward parameters from Ajallooeian et al. 2013,
which are not available to us. Instead :func:`search_reference` runs a grid of constant
parameter sets open loop in :class:`CPGParameterVectorEnv` (one vector env, one candidate per
env, no reset noise) and ranks them by *hop height*: the 90th percentile, over the second half
of the episode (after the transient), of the hip height above the standing height of the
nominal pose. :data:`REFERENCE_PARAMETERS` is the best of the default grid with the default
:class:`HopperConfig` among the candidates not on the edge of the action range
(:func:`choose_reference`), produced by ``cpg-actor cho2019-reference`` (which prints it and the
runners-up).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cpg_actor.robots.hopper import kinematics
from cpg_actor.robots.hopper.cho2019 import (
    PARAMETER_NAMES,
    CPGParameterVectorEnv,
    parameters_to_action,
)
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.task import NOMINAL_POSE

# nu_HFE, nu_KFE (Hz), rho_HFE, rho_KFE (rad), phi_HFE,KFE (rad): `cpg-actor cho2019-reference`
REFERENCE_PARAMETERS = (1.5, 1.5, 0.5, 0.6, -math.pi / 4)

DEFAULT_GRID = {
    "frequency": (1.0, 1.5, 2.0, 2.5, 3.0, 3.5),
    "amplitude_hip": (0.1, 0.2, 0.3, 0.4, 0.5),
    "amplitude_knee": (0.2, 0.4, 0.6, 0.8),
    "phase_bias": tuple(k * math.pi / 4 for k in range(-3, 5)),
}


@dataclass(frozen=True)
class Candidate:
    parameters: tuple[float, ...]  # in PARAMETER_NAMES order
    hop_height: float  # m
    episode_return: float


def grid_candidates(grid: dict[str, Sequence[float]] | None = None) -> np.ndarray:
    """All combinations of the grid as physical parameter rows ``(K, 5)``; both oscillators
    share one frequency (coupled oscillators lock to a common rhythm anyway)."""
    grid = {**DEFAULT_GRID, **(grid or {})}
    rows = [
        (f, f, rho_h, rho_k, min(max(phi, -math.pi), math.pi))
        for f, rho_h, rho_k, phi in itertools.product(
            grid["frequency"], grid["amplitude_hip"], grid["amplitude_knee"], grid["phase_bias"]
        )
    ]
    return np.array(rows, dtype=np.float64)


def evaluate_parameters(
    parameters: np.ndarray, config: HopperConfig | None = None, seed: int = 0
) -> list[Candidate]:
    """Run each row of ``parameters`` ``(K, 5)`` for one episode, open loop, no reset noise."""
    config = (config or HopperConfig()).replace(reset_noise=0.0)
    parameters = np.atleast_2d(np.asarray(parameters, dtype=np.float64))
    env = CPGParameterVectorEnv(len(parameters), config=config)
    try:
        env.reset(seed=seed)
        actions = parameters_to_action(parameters)
        heights = np.empty((config.episode_steps, len(parameters)))
        returns = np.zeros(len(parameters))
        for t in range(config.episode_steps):
            _, reward, terminated, truncated, info = env.step(actions)
            heights[t] = info["hip_height"]
            returns += reward
    finally:
        env.close()
    standing = float(kinematics.standing_hip_height(np.asarray(NOMINAL_POSE)))
    steady = heights[config.episode_steps // 2 :]
    hop = np.percentile(steady, 90, axis=0) - standing
    return [
        Candidate(tuple(float(v) for v in row), float(h), float(r))
        for row, h, r in zip(parameters, hop, returns, strict=True)
    ]


def search_reference(
    grid: dict[str, Sequence[float]] | None = None, config: HopperConfig | None = None
) -> list[Candidate]:
    """Every grid candidate, best hop height first."""
    candidates = evaluate_parameters(grid_candidates(grid), config)
    return sorted(candidates, key=lambda c: c.hop_height, reverse=True)


def interior(candidate: Candidate, margin: float = 0.1) -> bool:
    """Whether the candidate's action is at least ``margin`` inside [-1, 1]: a warm-start
    target on the clipping boundary would pull the Gaussian mean onto the edge."""
    action = parameters_to_action(np.asarray(candidate.parameters))
    return bool(np.all(np.abs(action) <= 1.0 - margin))


def choose_reference(candidates: Sequence[Candidate]) -> Candidate:
    """The highest-hopping candidate that lies inside the action range (see :func:`interior`)."""
    for candidate in candidates:
        if interior(candidate):
            return candidate
    raise ValueError("no candidate lies inside the action range; widen PARAMETER_RANGES")


def describe(parameters: Sequence[float]) -> str:
    return ", ".join(f"{n}={v:.3f}" for n, v in zip(PARAMETER_NAMES, parameters, strict=True))
