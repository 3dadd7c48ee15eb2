"""The terrain's height maps: each kind's shape, steps and slopes at its level, the grid's
layout, the same map from the same seed; the curriculum's promotion and demotion; bad input."""

import numpy as np
import pytest

from cpg_actor.terrain import (
    KINDS,
    Terrain,
    clamped_levels,
    difficulty,
    height_map,
    moved_levels,
    tile,
)

SMALL = {"tile_size": 6.0, "platform": 2.0, "border": 1.0, "levels": 4}


def small(**changes) -> Terrain:
    return Terrain(**{**SMALL, **changes}).validate()


def test_difficulty_grows_to_the_top_level():
    assert [difficulty(level, 4) for level in range(4)] == [0.25, 0.5, 0.75, 1.0]


@pytest.mark.parametrize("kind", KINDS)
def test_a_tile_has_one_sample_per_resolution_and_joins_its_neighbours_at_zero(kind):
    terrain = small()
    heights = tile(kind, 1.0, terrain, np.random.default_rng(0))
    assert heights.shape == (61, 61)  # 6 m at 0.1 m: 60 cells, 61 samples
    if kind != "rough":  # a pyramid: 0 on the edge, its platform flat
        edge = np.concatenate([heights[0], heights[-1], heights[:, 0], heights[:, -1]])
        assert np.abs(edge).max() == 0.0
        assert np.ptp(heights[20:41, 20:41]) == 0.0


def test_stairs_rise_in_steps_of_their_height_and_width():
    terrain = small(step_height=0.2, step_width=0.3)
    down = tile("stairs_down", 0.5, terrain, np.random.default_rng(0))
    profile = down[30, :31]  # from the edge (x = -3 m) to the centre, along x
    steps = np.unique(np.round(profile, 9))
    # (6 - 2) / 2 = 2 m from edge to platform: 6 whole treads of 0.3 m, 0.1 m each at level 0.5
    assert steps == pytest.approx(np.arange(7) * 0.1)
    treads = [np.sum(np.isclose(profile, h)) for h in steps[1:-1]]
    assert treads == [3] * 5  # 0.3 m: three samples each
    up = tile("stairs_up", 0.5, terrain, np.random.default_rng(0))
    assert up == pytest.approx(-down)  # the centre a pit
    assert down[30, 30] == pytest.approx(0.6) and up[30, 30] == pytest.approx(-0.6)


def test_slopes_rise_at_their_gradient_to_the_platform():
    terrain = small(slope=0.4)
    down = tile("slope_down", 0.5, terrain, np.random.default_rng(0))
    profile = down[30, :21]  # edge to platform edge, 2 m
    assert np.diff(profile) == pytest.approx(np.full(20, 0.2 * 0.1))  # 0.2 m per m
    assert down.max() == pytest.approx(0.4)
    up = tile("slope_up", 0.5, terrain, np.random.default_rng(0))
    assert up.min() == pytest.approx(-0.4) and up.max() == 0.0


def test_rough_tiles_stay_within_their_amplitude_and_are_random():
    terrain = small(roughness=0.1)
    heights = tile("rough", 0.5, terrain, np.random.default_rng(0))
    assert np.abs(heights).max() <= 0.025 + 1e-12 and heights.std() > 0.005
    other = tile("rough", 0.5, terrain, np.random.default_rng(1))
    assert not np.allclose(heights, other)
    # interpolated between samples two apart: no wall one sample wide
    assert np.abs(np.diff(heights, axis=1)).max() <= 0.025 + 1e-12


def test_the_grid_puts_levels_along_x_and_kinds_along_y_in_a_flat_border():
    terrain = small(kinds=("slope_down", "stairs_down"))
    ground = height_map(terrain)
    # 4 levels x 6 m + 2 x 1 m along x, 2 kinds x 6 m + 2 m along y, at 0.1 m
    assert ground.heights.shape == (141, 261)
    assert ground.origin == (-1.0, -1.0)
    border = np.concatenate([ground.heights[:10].ravel(), ground.heights[:, -10:].ravel()])
    assert np.abs(border).max() == 0.0
    for level in range(4):
        centre = ground.tile_centre(level, 1)  # stairs down: the platform on top
        assert ground.height_at(centre) == pytest.approx(6 * 0.2 * difficulty(level, 4))
        slope_top = ground.height_at(ground.tile_centre(level, 0))
        assert slope_top == pytest.approx(2.0 * 0.4 * difficulty(level, 4))
    # bilinear between samples, the edge's height beyond the map
    x = ground.tile_centre(3, 0)[0]
    assert ground.height_at(np.array([x - 2.95, 3.0])) == pytest.approx(0.4 * 0.05)
    assert ground.height_at(np.array([500.0, -500.0])) == 0.0


def test_the_same_terrain_gives_the_same_map_and_the_seed_another():
    first = height_map(small(kinds=("rough",)))
    again = height_map(small(kinds=("rough",)))
    other = height_map(small(kinds=("rough",), seed=1))
    assert np.array_equal(first.heights, again.heights)
    assert not np.array_equal(first.heights, other.heights)
    assert not first.heights.flags.writeable  # shared by every env: nobody writes it


def test_promotion_after_half_a_tile_demotion_under_half_the_commanded_distance():
    levels = np.array([2, 2, 2, 2, 0, 3])
    walked = np.array([4.1, 3.9, 3.9, 1.0, 0.0, 9.0])  # m from the start
    commanded = np.array([20.0, 7.0, 8.0, 0.0, 20.0, 20.0])  # |command| x episode seconds
    moved = moved_levels(levels, walked, commanded, tile_size=8.0)
    # out of the tile (> 4 m) up, even under half its command; 3.9 >= 3.5 stays; 3.9 < 4 down;
    # a zero command is never demoted; level 0 goes to -1 (clamped below); the top to 4
    assert moved.tolist() == [3, 2, 1, 2, -1, 4]
    clamped = clamped_levels(moved, 4, random_levels=np.full(6, 1))
    assert clamped.tolist() == [3, 2, 1, 2, 0, 1]  # past the top: the random level drawn


def test_flat_is_the_default():
    assert not Terrain().validate().active
    assert Terrain(kinds="all").validate().kinds == KINDS


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"kinds": ("stairs",)}, "unknown terrain kind 'stairs' in terrain.kinds; accepted: rough"),
        ({"kinds": ("rough", "rough")}, "a repeated kind"),
        ({"kinds": 3}, "terrain.kinds must be a list of"),
        ({"levels": 0}, "terrain.levels must be an integer from 1 to 1,000"),
        ({"start_level": 10}, "terrain.start_level must be a level in 0..9"),
        ({"start_level": -1}, "terrain.start_level must be an integer from 0 to"),
        ({"slope": -0.1}, "terrain.slope must be a finite number >= 0"),
        ({"tile_size": 8.05}, "terrain.tile_size must be a whole number of"),
        ({"platform": 8.0}, "terrain.platform must be at least 2 m"),
        ({"curriculum": "yes"}, "terrain.curriculum must be true or false"),
    ],
)
def test_bad_terrain_is_one_line_naming_what_is_accepted(changes, message):
    with pytest.raises(ValueError, match=message.replace(".", r"\.").replace("(", r"\(")) as error:
        Terrain(**{"kinds": ("rough",), **changes}).validate()
    assert "\n" not in str(error.value)


def test_unknown_terrain_keys_are_named():
    with pytest.raises(ValueError, match="unknown terrain key.s. level; accepted: kinds, levels"):
        Terrain.from_value({"level": 3})
