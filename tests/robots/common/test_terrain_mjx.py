"""Rough ground on MJX (JAX's CPU backend here): the robots start on their tiles and stand at
the MuJoCo env's heights over a stair platform, the curriculum moves the levels at the ends of
episodes, the level is in the saved state; floor contacts MJX cannot collide are refused."""

from __future__ import annotations

import numpy as np
import pytest

from cpg_actor.robots.common import mjx_runtime as runtime
from cpg_actor.robots.go1.config import Go1Config
from cpg_actor.robots.go1.vector import Go1VectorEnv
from cpg_actor.terrain import Terrain

if not runtime.available():
    pytest.skip('the MJX backend needs pip install -e ".[mjx]"', allow_module_level=True)

from cpg_actor.robots.go1.mjx import MjxGo1VectorEnv  # noqa: E402

# the MuJoCo env's test's small grid: env 0 on stairs down (platform 0.6 m up), env 1 on stairs
# up (0.6 m down); episodes of 0.2 s under a 0.5-1 m/s command (a robot standing still is sent
# down a level)
TERRAIN = {"levels": 2, "tile_size": 5.0, "platform": 3.0, "border": 1.0, "step_height": 0.2,
           "kinds": ["stairs_down", "stairs_up"], "start_level": 1}  # fmt: skip
CONFIG = {"reset_noise": 0.0, "episode_seconds": 0.2, "command_range": (0.5, 1.0),
          "terrain": TERRAIN}  # fmt: skip


@pytest.mark.slow
def test_mjx_starts_on_the_tiles_stands_over_the_ground_and_moves_the_levels():
    mjx = MjxGo1VectorEnv(2, {**CONFIG, "sim": "mjx"})
    cpu = Go1VectorEnv(2, CONFIG, num_threads=1)
    nominal = np.tile(np.asarray(cpu.quadruped.nominal_pose), (2, 1))
    mjx.reset(seed=0)
    cpu.reset(seed=0)
    centres = cpu.ground.map.tile_centre(np.array([1, 1]), np.array([0, 1]))
    state = mjx.jax_state
    assert np.asarray(state.ground.level).tolist() == [1, 1]
    assert np.abs(np.asarray(state.data.qpos[:, :2]) - centres).max() <= 1.0 + 1e-6
    for _ in range(5):  # standing: heights over the ground as the MuJoCo env's
        *_, info_mjx = mjx.step(nominal)
        *_, info_cpu = cpu.step(nominal)
    assert np.asarray(mjx.jax_state.data.qpos[:, 2]) - [0.6, -0.6] == pytest.approx(
        cpu.qpos[:, 2] - [0.6, -0.6], abs=5e-3)  # fmt: skip
    assert info_mjx["base_height"] == pytest.approx(info_cpu["base_height"], abs=5e-3)
    assert info_mjx["contact"].all()
    saved = mjx.get_state()
    for _ in range(5):  # the episode's end: standing still, both sent down to level 0
        *_, terminated, truncated, info = mjx.step(nominal)
    assert truncated.all() and not terminated.any()
    assert info["episode_metrics"]["terrain_level"].tolist() == [1.0, 1.0]
    assert np.asarray(mjx.jax_state.ground.level).tolist() == [0, 0]
    level_0 = cpu.ground.map.tile_centre(np.array([0, 0]), np.array([0, 1]))
    assert np.abs(np.asarray(mjx.jax_state.data.qpos[:, :2]) - level_0).max() <= 1.0 + 1e-6
    mjx.set_state(saved)
    assert np.asarray(mjx.jax_state.ground.level).tolist() == [1, 1]


def test_terrain_on_mjx_needs_the_feet_alone_on_the_ground():
    with pytest.raises(ValueError, match="terrain on MJX needs floor_contacts 'feet' or 'auto'"):
        Go1Config(sim="mjx", floor_contacts="all", terrain=Terrain(kinds=("rough",))).validate()
    assert Go1Config(sim="mjx", terrain=Terrain(kinds=("rough",))).validate().terrain.active
