"""Rough ground in the quadrupeds' MuJoCo env: the height field in the compiled model, a robot
standing on a stair tile's platform at its flat-ground height over it, the curriculum moving
levels at the ends of episodes, the level as an episode metric and in the saved state, the
flat default untouched, the terrain as a config section (MJX: test_terrain_mjx.py)."""

from __future__ import annotations

import numpy as np
import pytest

from cpg_actor.config import TrainConfig, apply_dict, parse_override
from cpg_actor.robots.anymal.vector import AnymalVectorEnv
from cpg_actor.robots.common.mujoco_runtime import mujoco
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.go1.config import Go1Config
from cpg_actor.robots.go1.vector import Go1VectorEnv
from cpg_actor.terrain import Terrain, height_map

# a small grid that compiles fast: 2 levels x 5 m, a 3 m platform (the starts are within 1 m
# of its centre, the feet within 0.4 m of the base)
SMALL = {"levels": 2, "tile_size": 5.0, "platform": 3.0, "border": 1.0, "step_height": 0.2}
ROBOTS = [(Go1VectorEnv, Go1Config), (AnymalVectorEnv, QuadrupedConfig)]


def terrain(**changes) -> dict:
    return {**SMALL, "kinds": ["stairs_down", "stairs_up", "rough"], **changes}


def stand(env, steps: int, seed: int = 0):
    """Reset, then hold the nominal pose for ``steps``: the last step's outputs."""
    env.reset(seed=seed)
    nominal = np.tile(np.asarray(env.quadruped.nominal_pose), (env.num_envs, 1))
    for _ in range(steps):
        out = env.step(nominal)
    return out


def test_the_ground_is_a_height_field_of_the_map_and_flat_stays_a_plane():
    config = Go1Config(terrain=Terrain(**terrain())).validate()
    env = Go1VectorEnv(1, config, num_threads=1)
    model, ground = env.model, env.model.geom("ground")
    assert model.nhfield == 1 and ground.type == mujoco.mjtGeom.mjGEOM_HFIELD
    assert ground.friction[0] == pytest.approx(config.foot_friction)
    heights = height_map(config.terrain).heights
    assert (model.hfield_nrow[0], model.hfield_ncol[0]) == heights.shape == (171, 121)
    # MuJoCo's samples, scaled by the elevation over the lowest point: the map's heights
    low, elevation = heights.min(), model.hfield_size[0, 2]
    stored = model.hfield_data.reshape(heights.shape) * elevation + low
    assert stored == pytest.approx(heights, abs=1e-6)
    flat = Go1VectorEnv(1, num_threads=1)
    assert flat.model.nhfield == 0 and flat.ground is None
    assert flat.model.geom("ground").type == mujoco.mjtGeom.mjGEOM_PLANE


@pytest.mark.parametrize(("env_class", "config_class"), ROBOTS)
def test_a_robot_on_a_stair_platform_stands_its_flat_height_above_it(env_class, config_class):
    # env 0 on the stairs down (the platform 3 treads of 0.3 m in, 3 x 0.2 m up at the top
    # level), env 1 on the stairs up (0.6 m down)
    config = config_class(reset_noise=0.0, terrain=Terrain(**terrain(start_level=1)))
    env = env_class(2, config.validate(), num_threads=1)
    flat = env_class(1, config_class(reset_noise=0.0).validate(), num_threads=1)
    *_, info = stand(env, 25)
    *_, flat_info = stand(flat, 25)
    assert env.qpos[:, 2] - np.array([0.6, -0.6]) == pytest.approx(
        np.full(2, flat.qpos[0, 2]), abs=3e-3)  # fmt: skip
    # the task's base height is over the ground: the flat one's
    assert info["base_height"] == pytest.approx(np.full(2, flat_info["base_height"][0]), abs=3e-3)
    assert info["contact"].all() and not info["episode_metrics"]["fell"][0] == 1.0
    # each on its tile, within 1 m of its centre
    centres = env.ground.map.tile_centre(np.array([1, 1]), np.array([0, 1]))
    assert np.abs(env.qpos[:, :2] - centres).max() <= 1.0 + 0.05


def test_the_curriculum_moves_levels_at_the_ends_of_episodes():
    # episodes of 0.2 s under commands of 0.5-1 m/s: a robot standing still walked less than
    # half the commanded 0.1-0.2 m, and goes one level down
    config = Go1Config(episode_seconds=0.2, command_range=(0.5, 1.0),
                       terrain=Terrain(**terrain(start_level=1, levels=3)))  # fmt: skip
    env = Go1VectorEnv(3, config.validate(), num_threads=1)
    obs, r, terminated, truncated, info = stand(env, 10)
    assert truncated.all()
    assert info["episode_metrics"]["terrain_level"].tolist() == [1.0, 1.0, 1.0]
    assert env.ground.levels.tolist() == [0, 0, 0]
    level_0 = env.ground.map.tile_centre(np.zeros(3), env.ground.columns)
    assert np.abs(env.qpos[:, :2] - level_0).max() <= 1.0 + 1e-9  # the next episode's tile
    # by hand: out of the tile up, past the top to a random level, none under a zero command
    ground, done = env.ground, np.array([True, True, False])
    ground.levels[:] = [1, 2, 1]
    qpos = np.zeros((3, env.model.nq))
    qpos[:, :2] = ground.start_xy + [[2.6, 0.0], [0.0, 2.6], [9.0, 0.0]]  # 2.6 m > 5 m / 2
    metric = ground.end_episodes(done, qpos, np.zeros((3, 3)), env.env_rngs)
    assert ground.levels[0] == 2 and ground.levels[1] in (0, 1, 2) and ground.levels[2] == 1
    assert metric[:2].tolist() == [1.0, 2.0] and np.isnan(metric[2])
    # without the curriculum the levels stay
    fixed = Go1VectorEnv(3, config.replace(terrain=Terrain(**terrain(start_level=1, levels=3,
                                                                     curriculum=False))),
                         num_threads=1)  # fmt: skip
    stand(fixed, 10)
    assert fixed.ground.levels.tolist() == [1, 1, 1]


def test_the_levels_are_in_the_saved_state_and_a_reset_starts_them_again():
    config = Go1Config(episode_seconds=0.2, command_range=(0.5, 1.0),
                       terrain=Terrain(**terrain(start_level=1))).validate()  # fmt: skip
    env = Go1VectorEnv(2, config, num_threads=1)
    stand(env, 10)
    state = env.get_state()
    assert env.ground.levels.tolist() == [0, 0]
    other = Go1VectorEnv(2, config, num_threads=1)
    other.reset(seed=5)
    assert other.ground.levels.tolist() == [1, 1]
    other.set_state(state)
    assert other.ground.levels.tolist() == [0, 0]
    assert other.ground.start_xy == pytest.approx(env.ground.start_xy)
    env.reset(seed=0)
    assert env.ground.levels.tolist() == [1, 1]


def test_the_terrain_is_a_config_section():
    config = TrainConfig()
    apply_dict(config, {"robot": "go1"}, prefix="")
    apply_dict(config, parse_override("env.terrain.kinds=[rough, stairs_up]"), prefix="")
    apply_dict(config, parse_override("env.terrain.levels=5"), prefix="")
    assert config.env.terrain.kinds == ("rough", "stairs_up") and config.env.terrain.levels == 5
    again = TrainConfig.from_dict(config.to_dict())  # as a run's config.yaml reads back
    assert again.env.terrain == config.env.terrain
    with pytest.raises(ValueError, match="unknown terrain kind 'ice'") as error:
        apply_dict(config, parse_override("env.terrain.kinds=[ice]"), prefix="")
    assert "\n" not in str(error.value)
    assert Go1Config(sim="mjx").validate().terrain == Terrain()  # flat: MJX as before


def test_a_model_with_other_actuators_is_the_compiled_one():
    # a randomised episode's model (motor strength) copies the last one compiled on the terrain
    # with its own actuators: every number as MuJoCo compiles it
    from cpg_actor.robots.common.perturbation import Perturbation
    from cpg_actor.robots.common.quadruped import ground
    from cpg_actor.robots.common.quadruped.vector import load_model

    config = Go1Config(terrain=Terrain(**terrain())).validate()
    nominal = load_model(Go1VectorEnv.quadruped, config)
    stronger = config.replace(perturbation=Perturbation(motor_strength=1.3, payload=2.0))
    copied = load_model(Go1VectorEnv.quadruped, stronger)
    ground._COMPILED.clear()
    compiled = load_model(Go1VectorEnv.quadruped, stronger)
    arrays = [n for n in dir(compiled) if isinstance(getattr(compiled, n), np.ndarray)]
    assert "hfield_data" in arrays and "actuator_gainprm" in arrays
    for name in arrays:
        assert np.array_equal(getattr(copied, name), getattr(compiled, name)), name
    assert not np.array_equal(copied.actuator_gainprm, nominal.actuator_gainprm)
