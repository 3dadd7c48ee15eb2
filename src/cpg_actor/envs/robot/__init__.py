"""The hopper's robot description: one Python data module, written out as MJCF and URDF.

``python -m cpg_actor.envs.robot`` regenerates ``cpg_actor/envs/assets/anymal_hopper.{xml,urdf}``
and the quadruped's ``anymal_b.xml``
(``--check`` only verifies they are up to date).
"""

from __future__ import annotations

from pathlib import Path

from cpg_actor.envs.robot import description
from cpg_actor.envs.robot.mjcf import mjcf_text
from cpg_actor.envs.robot.urdf import urdf_text

ASSETS_DIR = Path(__file__).resolve().parent.parent / "assets"
MJCF_PATH = ASSETS_DIR / f"{description.ROBOT_NAME}.xml"
URDF_PATH = ASSETS_DIR / f"{description.ROBOT_NAME}.urdf"


def generated_assets() -> dict[Path, str]:
    """Each shipped robot file and the text its description generates: the hopper's MJCF and
    URDF, and the quadruped's MJCF (:mod:`cpg_actor.envs.quadruped`)."""
    from cpg_actor.envs.quadruped import MJCF_PATH as QUADRUPED_MJCF_PATH
    from cpg_actor.envs.quadruped import mjcf_text as quadruped_mjcf_text

    return {
        MJCF_PATH: mjcf_text(),
        URDF_PATH: urdf_text(),
        QUADRUPED_MJCF_PATH: quadruped_mjcf_text(),
    }


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


__all__ = [
    "MJCF_PATH",
    "URDF_PATH",
    "description",
    "generated_assets",
    "mjcf_text",
    "stale_assets",
    "urdf_text",
    "write_assets",
]
