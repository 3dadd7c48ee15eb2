"""Rough ground for legged robots: the kinds and levels of a terrain (:class:`Terrain`), their
height maps as pure functions (:mod:`cpg_actor.terrain.heights`), legged_gym's curriculum
(:mod:`cpg_actor.terrain.curriculum`) and the MuJoCo height field of a map
(:mod:`cpg_actor.terrain.hfield`, imported on use: it needs MuJoCo). ``docs/quadruped.md``,
"Terrain", says how a quadruped env uses them."""

from cpg_actor.terrain.config import KINDS, Terrain, check_terrain
from cpg_actor.terrain.curriculum import clamped_levels, moved_levels
from cpg_actor.terrain.heights import HeightMap, difficulty, height_map, tile

__all__ = ["KINDS", "HeightMap", "Terrain", "check_terrain", "clamped_levels", "difficulty",
           "height_map", "moved_levels", "tile"]  # fmt: skip
