"""What rough ground a quadruped walks on (:class:`Terrain`, a quadruped config's ``terrain``),
with its validation. The defaults are flat ground: no kinds, no height field."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from cpg_actor.limits import (
    MAX_SEED,
    MAX_TERRAIN_LEVELS,
    MAX_TERRAIN_SAMPLES,
    brief,
    check_int,
)

# the kinds of tile, each a column of the grid (legged_gym's terrain types, Rudin et al. 2021),
# named as a robot walking out of the tile's centre meets them: "rough" random heights, a
# pyramid slope or stairs going up (the centre a pit) or down (the centre a platform)
KINDS = ("rough", "slope_up", "slope_down", "stairs_up", "stairs_down")
SIMULATORS = ("mujoco", "mjx")  # the simulators that take a terrain (docs/quadruped.md)


@dataclass
class Terrain:
    """A grid of tiles, one row per difficulty level (along x) and one column per kind (along
    y), as legged_gym lays it out, with a flat border around it. Level ``l`` of ``levels``
    has ``(l + 1) / levels`` of the top level's roughness, slope and step height.

    ``kinds`` empty (the default) is flat ground: the plane of the flat task, no height field.
    """

    kinds: tuple[str, ...] = ()  # of KINDS; "all" stands for every kind
    levels: int = 10  # difficulty levels, 0 the easiest
    # legged_gym's curriculum: promotion after walking more than half a tile, demotion after
    # less than half the distance the command asked for (cpg_actor.terrain.curriculum)
    curriculum: bool = True
    start_level: int = 0  # every env's first level (its only one without the curriculum)
    seed: int = 0  # the height maps' random numbers (the rough tiles)
    tile_size: float = 8.0  # m, a tile's side (legged_gym's)
    resolution: float = 0.1  # m between height samples (legged_gym's horizontal scale)
    border: float = 10.0  # m of flat ground around the grid
    platform: float = 3.0  # m, the side of the flat square at a slope's or stairs' centre
    roughness: float = 0.1  # m, peak to peak of the rough tiles at the top level
    slope: float = 0.4  # rise per metre of the slopes at the top level (about 22 degrees)
    step_height: float = 0.2  # m, a stair's rise at the top level
    step_width: float = 0.3  # m, a stair's tread (legged_gym's 0.31)

    @property
    def active(self) -> bool:
        """Whether there is rough ground (any kind)."""
        return len(self.kinds) > 0

    def validate(self) -> Terrain:
        """Raise ValueError naming the first bad field (``terrain.NAME``); returns ``self``."""
        kinds = self.kinds
        if isinstance(kinds, str):  # "all" or one kind, from YAML or --set
            kinds = (kinds,)
        if not (isinstance(kinds, list | tuple) and all(isinstance(k, str) for k in kinds)):
            raise ValueError(f"terrain.kinds must be a list of {', '.join(KINDS)} (or 'all'), "
                             f"got {brief(self.kinds)}")  # fmt: skip
        kinds = KINDS if tuple(kinds) == ("all",) else tuple(kinds)
        unknown = [k for k in kinds if k not in KINDS]
        if unknown or len(set(kinds)) != len(kinds):
            what = f"unknown terrain kind {brief(unknown[0])}" if unknown else "a repeated kind"
            raise ValueError(f"{what} in terrain.kinds; accepted: {', '.join(KINDS)} (or "
                             "'all'), each once")  # fmt: skip
        self.kinds = kinds
        check_int(self.levels, "terrain.levels", 1, MAX_TERRAIN_LEVELS)
        check_int(self.start_level, "terrain.start_level", 0, MAX_TERRAIN_LEVELS - 1)
        check_int(self.seed, "terrain.seed", 0, MAX_SEED)
        if self.start_level >= self.levels:
            raise ValueError(f"terrain.start_level must be a level in 0..{self.levels - 1} "
                             f"(terrain.levels={self.levels}), got {self.start_level}")  # fmt: skip
        if not isinstance(self.curriculum, bool):
            raise ValueError(f"terrain.curriculum must be true or false, got "
                             f"{brief(self.curriculum)}")  # fmt: skip
        for name in ("tile_size", "resolution", "border", "platform", "roughness", "slope",
                     "step_height", "step_width"):  # fmt: skip
            value = getattr(self, name)
            strict = name in ("tile_size", "resolution", "step_width")
            ok = not isinstance(value, bool) and isinstance(value, int | float)
            if not (ok and math.isfinite(value) and (value > 0 if strict else value >= 0)):
                raise ValueError(f"terrain.{name} must be a finite number "
                                 f"{'>' if strict else '>='} 0, got {brief(value)}")  # fmt: skip
            setattr(self, name, float(value))
        for name in ("tile_size", "border", "platform", "step_width"):
            cells = getattr(self, name) / self.resolution
            if cells > MAX_TERRAIN_SAMPLES:  # (and too large to round, if infinite)
                raise ValueError(
                    f"terrain.{name} is {cells:.3g} times terrain.resolution "
                    f"({self.resolution:g} m); at most {MAX_TERRAIN_SAMPLES:,} are accepted"
                )
            if abs(cells - round(cells)) > 1e-6:
                raise ValueError(
                    f"terrain.{name} must be a whole number of terrain.resolution "
                    f"({self.resolution:g} m), got {getattr(self, name):g}"
                )
        # the height map's samples, before it is made (cpg_actor.terrain.heights.height_map)
        tile, border = (round(getattr(self, name) / self.resolution)
                        for name in ("tile_size", "border"))  # fmt: skip
        samples = (self.levels * tile + 2 * border + 1) * (len(kinds) * tile + 2 * border + 1)
        if samples > MAX_TERRAIN_SAMPLES:
            raise ValueError(
                f"terrain.levels, tile_size, border and resolution ({self.levels}, "
                f"{self.tile_size:g} m, {self.border:g} m, {self.resolution:g} m) make a height "
                f"map of {samples:,} samples, above the {MAX_TERRAIN_SAMPLES:,} accepted; use "
                "fewer levels, smaller tiles or a coarser resolution"
            )
        if not 2.0 <= self.platform < self.tile_size:
            raise ValueError(f"terrain.platform must be at least 2 m (the robots start within "
                             f"1 m of its centre) and less than terrain.tile_size "
                             f"({self.tile_size:g} m), got {self.platform:g}")  # fmt: skip
        return self

    @classmethod
    def from_value(cls, value: Any) -> Terrain:
        """A :class:`Terrain` from itself or a mapping of its fields (a config file's);
        unknown keys are a ValueError listing the valid ones."""
        from cpg_actor.robots.common.checks import mapping_fields

        if isinstance(value, cls):
            return value
        return cls(**mapping_fields(cls, value, "terrain", sequences=("kinds",)))


def check_terrain(config: Any) -> None:
    """Validate an env config's ``terrain`` (converting a mapping from a config file) and the
    simulator that runs it: ValueError, one line, for a simulator without terrain."""
    config.terrain = Terrain.from_value(config.terrain).validate()
    if config.terrain.active and config.sim not in SIMULATORS:
        raise ValueError(
            f"terrain runs on {', '.join(SIMULATORS)}, got sim={brief(config.sim)}; give one of "
            "them, or no terrain.kinds for flat ground"
        )
    if config.terrain.active and config.sim == "mjx" and not getattr(config, "feet_only", True):
        raise ValueError(
            f"terrain on MJX needs floor_contacts 'feet' or 'auto' (the feet alone touch the "
            f"ground; MJX collides no height field with cylinders), got "
            f"floor_contacts={brief(config.floor_contacts)}"
        )
