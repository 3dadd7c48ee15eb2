"""The ground of an MJCF document as a MuJoCo height field (``hfield``) of a
:class:`~cpg_actor.terrain.heights.HeightMap`.

The robot's MJCF keeps its plane; :func:`compile_with_height_field` turns that geom (its
name, friction and material kept) into a height field over the map and compiles the model.
MuJoCo scales a height field's samples, stored in [0, 1], by its elevation and puts their 0 at
the geom's height: the map's lowest point. It collides each cell as two triangular prisms
(``base`` m deep below the lowest point), so a stair's riser is a slope one sample wide.
"""

from __future__ import annotations

import numpy as np

from cpg_actor.robots.common.mujoco_runtime import mujoco
from cpg_actor.terrain.heights import HeightMap

BASE = 1.0  # m: the depth of the prisms below the lowest point (nothing falls through)
HFIELD = "terrain"  # the height field asset's name


def compile_with_height_field(text: str, height_map: HeightMap,
                              ground: str = "ground") -> mujoco.MjModel:  # fmt: skip
    """The MjModel of the MJCF ``text`` whose geom ``ground`` is the height field of
    ``height_map`` (module docstring)."""
    heights = height_map.heights
    rows, columns = heights.shape
    low, high = float(heights.min()), float(heights.max())
    elevation = max(high - low, 1e-6)  # MuJoCo needs one; a flat map's samples are all 0
    half_x = (columns - 1) * height_map.resolution / 2
    half_y = (rows - 1) * height_map.resolution / 2
    spec = mujoco.MjSpec.from_string(text)
    spec.add_hfield(name=HFIELD, size=[half_x, half_y, elevation, BASE], nrow=rows,
                    ncol=columns, userdata=np.zeros(rows * columns).tolist())  # fmt: skip
    geom = spec.geom(ground)
    geom.type = mujoco.mjtGeom.mjGEOM_HFIELD
    geom.hfieldname = HFIELD
    geom.pos = [height_map.origin[0] + half_x, height_map.origin[1] + half_y, low]
    model = spec.compile()
    # the samples in [0, 1], row 0 at the map's lowest y (MuJoCo's order)
    model.hfield_data[:] = ((heights - low) / elevation).ravel()
    return model
