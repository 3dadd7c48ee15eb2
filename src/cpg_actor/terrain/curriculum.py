"""legged_gym's terrain curriculum (Rudin et al. 2021, ``_update_terrain_curriculum``), as pure
functions of each env's level and how far its robot walked in the episode that ended (numpy
arrays, or JAX arrays in the MJX env).

A robot that walked more than half a tile from where it started (out of its tile) moves one
level up; one that walked less than half the distance its command asked for over a whole
episode (``|command_xy| x episode_seconds / 2``) moves one level down (a promotion wins). A
level below 0 stays 0; one beyond the top goes to a level drawn uniformly from all of them,
so that robots that master the top level keep visiting the others (legged_gym's rule).
"""

from __future__ import annotations

import numpy as np

from cpg_actor.robots.common.array_namespace import namespace


def moved_levels(levels, walked, commanded, tile_size: float) -> np.ndarray:
    """(N,) int: each level after the episode, before clamping: ``levels`` (N,) plus one where
    ``walked`` (N, m from the start) exceeds ``tile_size / 2``, minus one where it is under
    half of ``commanded`` (N, m: the command's speed times the episode's length)."""
    levels = namespace(levels, walked, commanded).asarray(levels)
    up = walked > tile_size / 2
    down = (walked < commanded / 2) & ~up
    return levels + up.astype(levels.dtype) - down.astype(levels.dtype)


def clamped_levels(moved, num_levels: int, random_levels) -> np.ndarray:
    """(N,) int: ``moved`` (:func:`moved_levels`) within 0 .. num_levels - 1: below 0 is 0,
    past the top is ``random_levels`` (N, drawn uniformly in 0 .. num_levels - 1)."""
    xp = namespace(moved, random_levels)
    return xp.where(moved >= num_levels, random_levels, xp.maximum(moved, 0))
