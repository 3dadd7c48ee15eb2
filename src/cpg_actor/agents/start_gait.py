"""Where a CPG agent starts: ``agent_config.start_gait`` resolved to CPG parameters.

A gait is the open-loop CPG's physical parameters in the form of ``agent_config.cpg_initial``
(``frequency``, ``amplitude``, ``convergence``, ``coupling_weight``, ``phase_bias``, ...). The
CPG-Actor starts its CPG there, ``cho2019-warm`` fits its actor toward the gait's frequency,
amplitude and phase bias, and ``mlp-warm`` toward the joint motion the gait makes, so that
the agents differ in their method and not in their prior.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from cpg_actor.agents.gait_file import load_gait
from cpg_actor.robots.plugin import Robot

SEARCH = "search"  # the packaged gait found by the open-loop search for the robot


def read_gait(path: str | Path) -> dict[str, Any]:
    """The CPG parameters (``cpg_initial``) of a gait file or a search run's directory
    (:func:`cpg_actor.agents.gait_file.load_gait`); one clear ValueError for a missing or
    malformed file."""
    try:
        return dict(load_gait(path)["cpg_initial"])
    except FileNotFoundError as error:
        raise ValueError(f"{error} (agent_config.start_gait)") from None


def packaged_gait_path(path: Path | None, robot: str) -> Path:
    """The gait shipped with robot ``robot`` at ``path`` (its ``Robot.start_gait``)."""
    if path is None or not path.is_file():
        raise ValueError(
            f"agent_config.start_gait 'search': no gait is shipped for robot '{robot}'; "
            "run `cpg-actor train --agent open-loop-es` and pass its gait.yaml, or leave "
            "start_gait empty (the CPG preset)"
        )
    return path


def start_parameters(start_gait: str, plugin: Robot) -> dict[str, Any]:
    """The CPG parameters ``start_gait`` names on the run's robot ``plugin``: ``{}`` for ""
    (the preset), its packaged gait (``Robot.start_gait``) for "search", else the gait file
    at that path."""
    if not start_gait:
        return {}
    if start_gait == SEARCH:
        return read_gait(packaged_gait_path(plugin.start_gait, plugin.name))
    return read_gait(start_gait)


def search_steps(start_gait: str, plugin: Robot) -> int:
    """The env steps the search behind ``start_gait`` took (the gait file's
    ``steps_searched``, else ``steps``), on the run's robot ``plugin``; 0 for the preset.
    What ``TrainConfig.search_steps`` counts when a comparison charges a start's search to the
    agents that use it."""
    if not start_gait:
        return 0
    path = start_gait
    if start_gait == SEARCH:
        path = packaged_gait_path(plugin.start_gait, plugin.name)
    try:
        gait = load_gait(path)
    except FileNotFoundError as error:
        raise ValueError(f"{error} (agent_config.start_gait)") from None
    return int(gait.get("steps_searched", gait["steps"]))


def hopper_gait_parameters(gait: dict[str, Any]) -> tuple[float, float, float, float, float]:
    """``(nu_HFE, nu_KFE, rho_HFE, rho_KFE, phi_HFE,KFE)`` of a hopper gait: what the Cho et
    al. baseline's actions set."""

    def pair(value: Any) -> tuple[float, float]:
        if isinstance(value, (int, float)):
            return float(value), float(value)
        return float(value[0]), float(value[1])

    nu, rho = pair(gait["frequency"]), pair(gait["amplitude"])
    phi = gait.get("phase_bias", 0.0)
    phi = float(phi) if isinstance(phi, (int, float)) else float(phi[0][1])
    phi = math.remainder(phi, 2 * math.pi)
    return nu[0], nu[1], rho[0], rho[1], phi
