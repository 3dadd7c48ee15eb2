"""The rough ground of a quadruped's MuJoCo env (``config.terrain`` with kinds): where each
robot starts, how high it stands above the ground, and legged_gym's curriculum over the levels.

:class:`Ground` is what :class:`~cpg_actor.robots.common.quadruped.vector.QuadrupedVectorEnv`
holds when its config has a terrain (None on flat ground, which then runs exactly as without
this module). Env ``i`` walks the tiles of kind ``i % len(kinds)`` (a column of the grid) and
starts each episode on its level's tile, within 1 m of the tile's centre (uniform in x and y,
drawn from the env's generator after its start pose and command: the flat task's draws come
first), its feet on the ground. The task reads heights relative to the ground
(:meth:`Ground.relative`): the base's over the mean ground height under its four feet (the
base height reward and the fall check), each foot's over the ground under it (contact). The
observation is unchanged: what a blind robot measures.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from cpg_actor.robots.common.mujoco_runtime import mujoco
from cpg_actor.tasks import velocity as task
from cpg_actor.terrain import Terrain, clamped_levels, height_map, moved_levels

SPAWN_SPREAD = 1.0  # m: a start within this of the tile's centre in x and y (legged_gym's)


def _outside_actuators(text: str) -> str:
    """``text`` without its ``<actuator>`` element."""
    head, _, rest = text.partition("<actuator>")
    return head + rest.partition("</actuator>")[2]


# the last model compiled on each terrain, with its MJCF: another model that differs from it only
# in its actuators (a randomised episode's motor strength) is a copy of it with theirs
_COMPILED: dict[tuple, tuple[str, mujoco.MjModel]] = {}


def terrain_model(text: str, terrain: Terrain) -> mujoco.MjModel:
    """The MjModel of a quadruped's MJCF ``text`` on ``terrain``'s ground. Compiling a height
    field of the default grid's size takes MuJoCo about 0.1 s, too long for each randomised
    episode: a model whose MJCF differs from the last one on this terrain only in its actuators
    is a copy of that one with its own actuator arrays (``actuator_*``, from the MJCF compiled
    on the plane, fast): the same numbers as compiled (``tests/robots/common/``)."""
    from cpg_actor.terrain.hfield import compile_with_height_field

    key = tuple(sorted(vars(terrain).items()))
    last = _COMPILED.get(key)
    if last is not None and _outside_actuators(last[0]) == _outside_actuators(text):
        model = copy.copy(last[1])
        if last[0] != text:
            own = mujoco.MjModel.from_xml_string(text)
            for name in dir(own):
                if name.startswith("actuator_") and isinstance(getattr(own, name), np.ndarray):
                    getattr(model, name)[...] = getattr(own, name)
        return model
    model = compile_with_height_field(text, height_map(terrain))
    if len(_COMPILED) >= 4:
        _COMPILED.pop(next(iter(_COMPILED)))
    _COMPILED[key] = (text, model)
    return copy.copy(model)


class Ground:
    """Each env's tile and level on ``terrain``, for ``num_envs`` robots of ``quadruped``
    whose episodes last ``episode_seconds`` (module docstring)."""

    def __init__(self, terrain: Terrain, num_envs: int, episode_seconds: float) -> None:
        self.terrain = terrain
        self.map = height_map(terrain)
        self.episode_seconds = episode_seconds
        self.levels = np.full(num_envs, terrain.start_level, dtype=np.int64)
        self.columns = np.arange(num_envs) % len(terrain.kinds)
        self.start_xy = np.zeros((num_envs, 2))  # where each episode started

    def restart(self) -> None:
        """Every env back on the first level (a reset of the env)."""
        self.levels[:] = self.terrain.start_level

    def place(self, model, data, index: int, rng: np.random.Generator, quadruped) -> None:
        """Put robot ``index`` (its joints already in ``data.qpos``) on its tile, near the
        centre, its lowest foot on the ground."""
        centre = self.map.tile_centre(self.levels[index], self.columns[index])
        data.qpos[:2] = centre + rng.uniform(-SPAWN_SPREAD, SPAWN_SPREAD, 2)
        data.qpos[2] = 0.0
        mujoco.mj_kinematics(model, data)
        feet = np.array([data.site(f"{leg}_foot").xpos for leg in quadruped.legs])
        clearance = feet[:, 2] - self.map.height_at(feet[:, :2])
        data.qpos[2] += quadruped.foot_radius - clearance.min()
        self.start_xy[index] = data.qpos[:2]

    def relative(self, reading: task.Reading) -> task.Reading:
        """``reading`` with heights above the ground: the base's over the mean height under the
        feet, each foot's over the height under it."""
        feet = reading.feet.copy()
        under = self.map.height_at(feet[:, :, :2])  # (N, 4)
        feet[:, :, 2] -= under
        qpos = reading.qpos.copy()
        qpos[:, 2] -= under.mean(axis=1)
        return reading._replace(qpos=qpos, feet=feet)

    def end_episodes(self, done: np.ndarray, qpos: np.ndarray, command: np.ndarray,
                     rngs: list[np.random.Generator]) -> np.ndarray:  # fmt: skip
        """The curriculum (:mod:`cpg_actor.terrain.curriculum`) for the envs whose episode
        ended (``done``, N), their bases now at ``qpos[:, :2]`` under ``command`` (N, 3);
        returns the levels they walked (N, NaN elsewhere), the ``terrain_level`` metric."""
        walked_level = np.where(done, self.levels.astype(float), np.nan)
        if not self.terrain.curriculum or not done.any():
            return walked_level
        index = np.flatnonzero(done)
        walked = np.linalg.norm(qpos[index, :2] - self.start_xy[index], axis=1)
        walked = np.nan_to_num(walked, nan=0.0)  # a simulation that blew up walked nowhere
        commanded = np.linalg.norm(command[index, :2], axis=1) * self.episode_seconds
        moved = moved_levels(self.levels[index], walked, commanded, self.terrain.tile_size)
        top = self.terrain.levels
        # a draw only for the robots past the top level (the env's generator)
        random = [rngs[i].integers(top) if m >= top else 0
                  for i, m in zip(index, moved, strict=True)]  # fmt: skip
        self.levels[index] = clamped_levels(moved, top, np.asarray(random, dtype=np.int64))
        return walked_level

    def get_state(self) -> dict[str, Any]:
        return {"terrain_level": self.levels.copy(), "terrain_start": self.start_xy.copy()}

    def set_state(self, state: dict[str, Any]) -> None:
        if "terrain_level" in state:
            self.levels[:] = np.asarray(state["terrain_level"])
            self.start_xy[:] = np.asarray(state["terrain_start"])
