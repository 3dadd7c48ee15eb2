"""Beyond the paper: the ANYmal B quadruped (floating base, four legs of HAA, HFE and KFE) and a
forward-walking task on MuJoCo, for CPG gaits (``docs/quadruped.md``).

``python -m cpg_actor.envs.robot`` regenerates the shipped MJCF
(``cpg_actor/envs/assets/anymal_b.xml``, with the hopper's files; ``--check`` only verifies
they are up to date).
"""

from __future__ import annotations

from pathlib import Path

from cpg_actor.envs.quadruped import description
from cpg_actor.envs.quadruped.config import QuadrupedConfig
from cpg_actor.envs.quadruped.mjcf import mjcf_text

MJCF_PATH = Path(__file__).resolve().parent.parent / "assets" / f"{description.ROBOT_NAME}.xml"

__all__ = ["MJCF_PATH", "QuadrupedConfig", "description", "mjcf_text"]
