"""Height maps of rough ground, as pure functions of numpy arrays (heights in m).

One tile is a square of ``n + 1`` by ``n + 1`` height samples, ``resolution`` apart, in
coordinates ``(u, v)`` from its centre; each kind of :data:`~cpg_actor.terrain.config.KINDS`
is a function of them and a ``difficulty`` in (0, 1] (legged_gym's terrain types, Rudin et al.
2021, with the sizes of :class:`~cpg_actor.terrain.config.Terrain`):

* ``rough``: heights uniform in +-difficulty x roughness / 2, drawn every two samples and
  interpolated linearly between them (no wall one sample wide);
* ``slope_up`` / ``slope_down``: a pyramid whose flat ``platform`` at the centre is the bottom
  (up) or the top (down) of slopes of difficulty x slope rise per metre, reaching height 0 at
  the tile's edge;
* ``stairs_up`` / ``stairs_down``: the same pyramid in steps ``step_width`` wide and difficulty
  x step_height high, ``(tile - platform) / 2 // step_width`` of them from edge to platform.

Every tile but the rough ones is 0 on its edge, so that tiles join without a wall. The grid
(:func:`height_map`) puts level ``l`` in the row of tiles from x = l tile to (l + 1) tile and
kind ``k`` in the column from y = k tile to (k + 1) tile, with a flat border around them.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np

from cpg_actor.robots.common.array_namespace import namespace
from cpg_actor.terrain.config import KINDS, Terrain


def difficulty(level: int, levels: int) -> float:
    """The share of the top level's roughness, slope and step height at ``level`` (0-based) of
    ``levels``: ``(level + 1) / levels``, so that the easiest level is not quite flat."""
    return (level + 1) / levels


def tile_coordinates(n: int, resolution: float) -> tuple[np.ndarray, np.ndarray]:
    """``(u, v)``, each (n + 1, n + 1): a tile's sample positions from its centre (m), ``u``
    along x (columns) and ``v`` along y (rows)."""
    axis = np.arange(n + 1) * resolution - n * resolution / 2
    return np.meshgrid(axis, axis)


def pyramid_distance(u: np.ndarray, v: np.ndarray, tile_size: float, platform: float):
    """How far inside the tile's edge each sample lies (m), capped at the platform's edge:
    ``min(tile/2 - max(|u|, |v|), (tile - platform) / 2)``, at least 0."""
    inside = tile_size / 2 - np.maximum(np.abs(u), np.abs(v))
    return np.clip(inside, 0.0, (tile_size - platform) / 2)


def rough(u, v, level_difficulty: float, terrain: Terrain, rng: np.random.Generator):
    """Random heights uniform in +-roughness x difficulty / 2, drawn on a lattice two samples
    apart and interpolated bilinearly."""
    n = u.shape[0] - 1
    coarse_axis = np.arange(0, n + 2, 2)  # sample indices of the lattice (past the end if odd)
    half = terrain.roughness * level_difficulty / 2
    coarse = rng.uniform(-half, half, (len(coarse_axis), len(coarse_axis)))
    fine = np.arange(n + 1)
    rows = np.stack([np.interp(fine, coarse_axis, row) for row in coarse])  # along x
    return np.stack([np.interp(fine, coarse_axis, column) for column in rows.T], axis=1)


def slope(u, v, level_difficulty: float, terrain: Terrain, up: bool):
    """A pyramid of slopes rising ``slope x difficulty`` per metre towards the platform (down:
    the centre on top) or sinking (up: the centre a pit)."""
    depth = pyramid_distance(u, v, terrain.tile_size, terrain.platform)
    heights = terrain.slope * level_difficulty * depth
    return -heights if up else heights


def stairs(u, v, level_difficulty: float, terrain: Terrain, up: bool):
    """A pyramid of stairs, ``step_height x difficulty`` per step, rising towards the platform
    (down: the centre on top) or sinking (up: the centre a pit)."""
    depth = pyramid_distance(u, v, terrain.tile_size, terrain.platform)
    steps = np.floor(depth / terrain.step_width + 1e-9)  # whole treads between edge and sample
    heights = terrain.step_height * level_difficulty * steps
    return -heights if up else heights


def tile(kind: str, level_difficulty: float, terrain: Terrain, rng: np.random.Generator):
    """The (n + 1, n + 1) heights (m) of one tile of ``kind`` (rows along y); ValueError for a
    kind not in :data:`~cpg_actor.terrain.config.KINDS`."""
    n = round(terrain.tile_size / terrain.resolution)
    u, v = tile_coordinates(n, terrain.resolution)
    if kind == "rough":
        return rough(u, v, level_difficulty, terrain, rng)
    if kind in ("slope_up", "slope_down"):
        return slope(u, v, level_difficulty, terrain, up=kind == "slope_up")
    if kind in ("stairs_up", "stairs_down"):
        return stairs(u, v, level_difficulty, terrain, up=kind == "stairs_up")
    raise ValueError(f"unknown terrain kind {kind!r}; accepted: {', '.join(KINDS)}")


class HeightMap(NamedTuple):
    """The whole ground: ``heights`` (rows along y, columns along x, m) sampled
    ``resolution`` apart from the corner ``origin`` (x, y), and the grid's tiles."""

    heights: np.ndarray
    origin: tuple[float, float]
    resolution: float
    tile_size: float
    levels: int
    kinds: tuple[str, ...]

    def tile_centre(self, level, column) -> np.ndarray:
        """(..., 2) the centre (x, y) of the tile at ``level`` and kind ``column`` (arrays;
        numpy or JAX, as :meth:`height_at`)."""
        xp = namespace(level, column)
        return xp.stack([(xp.asarray(level) + 0.5) * self.tile_size,
                         (xp.asarray(column) + 0.5) * self.tile_size], axis=-1)  # fmt: skip

    def height_at(self, xy: np.ndarray) -> np.ndarray:
        """(...) the ground's height (m) under the points ``xy`` (..., 2): bilinear between the
        samples, the edge's height beyond the map. numpy, or JAX for a map whose ``heights``
        is a JAX array (the MJX env's)."""
        xp = namespace(xy, self.heights)
        rows, columns = self.heights.shape
        x = xp.clip((xy[..., 0] - self.origin[0]) / self.resolution, 0, columns - 1)
        y = xp.clip((xy[..., 1] - self.origin[1]) / self.resolution, 0, rows - 1)
        x0 = xp.minimum(xp.floor(x).astype(int), columns - 2)
        y0 = xp.minimum(xp.floor(y).astype(int), rows - 2)
        fx, fy = x - x0, y - y0
        h = self.heights
        bottom = h[y0, x0] * (1 - fx) + h[y0, x0 + 1] * fx
        top = h[y0 + 1, x0] * (1 - fx) + h[y0 + 1, x0 + 1] * fx
        return bottom * (1 - fy) + top * fy


def height_map(terrain: Terrain) -> HeightMap:
    """The grid of ``terrain`` (validated, with kinds): its tiles from ``terrain.seed`` (level
    by level, kind by kind), the flat border around them. The same terrain gives the same map."""
    return _height_map(tuple(sorted(vars(terrain).items())))


@functools.lru_cache(maxsize=4)  # every env (and a randomised env's every model) shares one
def _height_map(fields: tuple) -> HeightMap:
    terrain = Terrain(**dict(fields))
    n = round(terrain.tile_size / terrain.resolution)
    border = round(terrain.border / terrain.resolution)
    columns = terrain.levels * n + 2 * border + 1  # along x
    rows = len(terrain.kinds) * n + 2 * border + 1  # along y
    heights = np.zeros((rows, columns))
    rng = np.random.default_rng(terrain.seed)
    for level in range(terrain.levels):
        for column, kind in enumerate(terrain.kinds):
            y, x = border + column * n, border + level * n
            share = difficulty(level, terrain.levels)
            heights[y : y + n + 1, x : x + n + 1] = tile(kind, share, terrain, rng)
    heights.setflags(write=False)
    return HeightMap(heights, (-terrain.border, -terrain.border), terrain.resolution,
                     terrain.tile_size, terrain.levels, terrain.kinds)  # fmt: skip
