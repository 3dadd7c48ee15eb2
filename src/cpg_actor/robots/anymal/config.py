"""ANYmal B's env config: the quadruped's (:class:`~cpg_actor.robots.common.quadruped.config.
QuadrupedConfig`, whose numbers are ANYmal B's) with the recipes only ANYmal B has."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from cpg_actor.robots.anymal.legged_gym import LEGGED_GYM
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig


@dataclass
class AnymalConfig(QuadrupedConfig):
    # legged_gym's ANYmal B recipe, its env values (--preset legged_gym; legged_gym.py gives
    # each its source and the departures)
    LEGGED_GYM: ClassVar[dict[str, Any] | None] = LEGGED_GYM
