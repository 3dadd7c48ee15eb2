"""The simulator files shipped with the robots (MJCF, URDF), each generated from its robot's
description: ``python -m cpg_actor.robots`` rewrites them, ``--check`` only reports those that
differ from what the descriptions generate."""

from __future__ import annotations

from pathlib import Path

from cpg_actor.robots.registry import ROBOTS


def generated_assets() -> dict[Path, str]:
    """Each shipped robot file and the text its description generates, for every robot."""
    return {path: text for robot in ROBOTS.values() for path, text in robot.assets().items()}


def stale_assets() -> list[Path]:
    """Shipped robot files that differ from what the description generates."""
    return [
        path
        for path, text in generated_assets().items()
        if not path.exists() or path.read_text() != text
    ]


def write_assets() -> list[Path]:
    """(Re)write the robot files; returns those that changed."""
    changed = stale_assets()
    for path, text in generated_assets().items():
        if path in changed:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(path.suffix + ".tmp")
            tmp.write_text(text)
            tmp.replace(path)
    return changed
