"""Rough ground in the quadrupeds' MJX env: what :mod:`~cpg_actor.robots.common.quadruped.ground`
does for the MuJoCo env, as pure JAX functions of each env's :class:`GroundState`.

The same height map (the same :class:`~cpg_actor.terrain.heights.HeightMap`, its heights a JAX
array), tiles, curriculum (:mod:`cpg_actor.terrain.curriculum`, on JAX arrays) and heights over
the ground; the start's offset on the tile and the level drawn for a robot past the top come
from keys folded out of each env's (the flat task's draws unchanged). The base touching the
ground is a corner of the model's ``base_box`` at or under the ground's height there.
"""

from __future__ import annotations

from typing import Any, NamedTuple

from cpg_actor.robots.common.mjx_runtime import load
from cpg_actor.robots.common.quadruped.ground import SPAWN_SPREAD
from cpg_actor.tasks import velocity as task
from cpg_actor.terrain import Terrain, clamped_levels, height_map, moved_levels

jax, mjx = load()
jnp = jax.numpy

SPAWN_FOLD, LEVEL_FOLD = 101, 102  # the folds of an env's key for its start and its new level


class GroundState(NamedTuple):
    """Each env's level and where its episode started (N rows each)."""

    level: Any  # (N,) int32
    start_xy: Any  # (N, 2) m


class MjxGround:
    """The terrain of an MJX env whose episodes last ``episode_seconds``."""

    def __init__(self, terrain: Terrain, episode_seconds: float) -> None:
        self.terrain = terrain
        ground = height_map(terrain)
        self.map = ground._replace(heights=jnp.asarray(ground.heights, dtype=jnp.float32))
        self.episode_seconds = episode_seconds

    def first_levels(self, num_envs: int):
        return jnp.full(num_envs, self.terrain.start_level, dtype=jnp.int32)

    def columns(self, num_envs: int):
        return jnp.arange(num_envs, dtype=jnp.int32) % len(self.terrain.kinds)

    def place(self, model, data, key, level, column, feet, foot_radius: float):
        """One robot's ``data`` (its joints set) on its tile near the centre, its lowest foot
        on the ground; the kinematics after the move (for the feet's positions)."""
        offset = jax.random.uniform(jax.random.fold_in(key, SPAWN_FOLD), (2,),
                                    minval=-SPAWN_SPREAD, maxval=SPAWN_SPREAD)  # fmt: skip
        qpos = data.qpos.at[:2].set(self.map.tile_centre(level, column) + offset).at[2].set(0.0)
        placed = mjx.kinematics(model, data.replace(qpos=qpos))
        clearance = placed.site_xpos[feet, 2] - self.map.height_at(placed.site_xpos[feet, :2])
        qpos = qpos.at[2].add(foot_radius - clearance.min())
        return qpos, placed

    def relative(self, reading: task.Reading, corners) -> task.Reading:
        """``reading`` with heights over the ground (the MuJoCo env's :meth:`Ground.relative`)
        and the base touching it where a corner (N, 8, 3) is at or under it."""
        under = self.map.height_at(reading.feet[:, :, :2])  # (N, 4)
        feet = reading.feet.at[:, :, 2].add(-under)
        qpos = reading.qpos.at[:, 2].add(-under.mean(axis=1))
        below = corners[:, :, 2] - self.map.height_at(corners[:, :, :2])
        return reading._replace(qpos=qpos, feet=feet, base_touch=below.min(axis=1) <= 0.0)

    def end_episodes(self, ground: GroundState, done, qpos, command, keys):
        """The levels after the episodes that ended (``done``), their bases at ``qpos`` under
        ``command``; and each env's level as the ``terrain_level`` metric (NaN elsewhere)."""
        metric = jnp.where(done, ground.level.astype(jnp.float32), jnp.nan)
        if not self.terrain.curriculum:
            return ground.level, metric
        walked = jnp.linalg.norm(qpos[:, :2] - ground.start_xy, axis=1)
        walked = jnp.nan_to_num(walked, nan=0.0)
        commanded = jnp.linalg.norm(command[:, :2], axis=1) * self.episode_seconds
        moved = moved_levels(ground.level, walked, commanded, self.terrain.tile_size)
        top = self.terrain.levels
        random = jax.vmap(lambda key: jax.random.randint(
            jax.random.fold_in(key, LEVEL_FOLD), (), 0, top, dtype=jnp.int32))(keys)  # fmt: skip
        level = clamped_levels(moved, top, random).astype(jnp.int32)
        return jnp.where(done, level, ground.level), metric
