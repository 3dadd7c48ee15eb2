"""The hopper's parts of the paper's reproduction (its ``Robot.paper``): eq. 4's reward terms,
the open-loop grid floor over Cho et al.'s constant CPG parameters, and its joint limits for
traces saved without their action bounds."""

from __future__ import annotations

from typing import Any

import numpy as np

from cpg_actor.robots.hopper.description import JOINT_LIMITS, JOINT_NAMES
from cpg_actor.robots.hopper.reward import REWARD_TERMS
from cpg_actor.robots.plugin import Paper


def open_loop_floor(env_config: Any, grid: dict | None = None) -> dict[str, Any]:
    """The best candidate of the grid (:data:`~cpg_actor.robots.hopper.cho2019_reference.
    DEFAULT_GRID`, ``grid`` entries replacing its own) by episode return, and for reference by
    hop height, each run open loop for one episode with no reset noise."""
    from cpg_actor.robots.hopper.cho2019 import PARAMETER_NAMES
    from cpg_actor.robots.hopper.cho2019_reference import evaluate_parameters, grid_candidates

    candidates = evaluate_parameters(grid_candidates(grid), env_config)
    by_return = max(candidates, key=lambda c: c.episode_return)
    by_hop = max(candidates, key=lambda c: c.hop_height)

    def row(candidate) -> dict[str, Any]:
        return {
            "parameters": dict(zip(PARAMETER_NAMES, candidate.parameters, strict=True)),
            "episode_return": candidate.episode_return,
            "hop_height_p90": candidate.hop_height,
        }

    return {"candidates": len(candidates), "best_return": row(by_return), "best_hop": row(by_hop)}


def joint_limits(joints: tuple[str, ...] | None) -> tuple[np.ndarray, np.ndarray] | None:
    """The hopper's joint limits (low, high) for traces of ``joints`` (None: the hopper's);
    None for another robot's joints."""
    joints = tuple(JOINT_NAMES) if joints is None else joints
    if joints != tuple(JOINT_NAMES):
        return None
    limits = np.array([JOINT_LIMITS[name] for name in joints], dtype=float)
    return limits[:, 0], limits[:, 1]


PAPER = Paper(reward_terms=REWARD_TERMS, open_loop_floor=open_loop_floor, joint_limits=joint_limits)
