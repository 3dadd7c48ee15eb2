"""A trained run's saved configuration, read back leniently: its ``config.yaml`` as a mapping
and the robot it names (for reading many runs, e.g. a folder of seeds, where one unreadable
file must not stop the others; :func:`cpg_actor.config.read_config_file` refuses such a
file)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from cpg_actor.robots.plugin import Robot
from cpg_actor.robots.registry import DEFAULT_ROBOT, get_robot
from cpg_actor.safe_yaml import read_yaml


def read_config(run_dir: Path) -> dict[str, Any]:
    """A run's saved ``config.yaml`` as a mapping (empty if it has none)."""
    try:
        data = read_yaml(Path(run_dir) / "config.yaml") or {}
    except (OSError, ValueError):  # unreadable, not YAML, beyond the YAML bounds
        return {}
    return data if isinstance(data, dict) else {}


def run_robot(config: dict[str, Any]) -> Robot:
    """The robot of a run's saved config (``robot``; the default robot where not saved)."""
    return get_robot(config.get("robot") or DEFAULT_ROBOT)
