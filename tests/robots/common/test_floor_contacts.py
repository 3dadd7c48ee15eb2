"""`env.floor_contacts`: which of a quadruped's geoms touch the floor."""

import numpy as np
import pytest

from cpg_actor.config import TrainConfig
from cpg_actor.robots.common.quadruped.vector import load_model
from cpg_actor.robots.go1.vector import GO1


def colliding(config) -> set[str]:
    """The names of the robot's geoms that can touch the floor (unnamed ones by their id)."""
    model = load_model(GO1, config, torque_control=config.sim == "mjx")
    floor = model.geom("ground").id
    return {
        model.geom(g).name or str(g)
        for g in range(model.ngeom)
        if g != floor
        and (model.geom_contype[g] & model.geom_conaffinity[floor]
             or model.geom_conaffinity[g] & model.geom_contype[floor])
    }  # fmt: skip


FEET = {f"{leg}_foot" for leg in GO1.legs}


def test_auto_is_the_feet_alone_on_mjx_and_every_geom_on_mujoco():
    config = GO1.config_class()
    assert config.floor_contacts == "auto"
    on_mujoco = colliding(config)
    assert FEET < on_mujoco and len(on_mujoco) > 20  # the trunk, hips, thighs and calves too
    assert colliding(config.replace(sim="mjx")) == FEET
    assert colliding(config.replace(floor_contacts="feet")) == FEET
    assert colliding(config.replace(sim="mjx", floor_contacts="all")) == on_mujoco


def test_the_feet_alone_change_nothing_while_only_the_feet_touch():
    """A standing robot's first second is the same with the feet alone as with every geom."""
    import mujoco

    config = GO1.config_class()
    traces = []
    for floor in ("all", "feet"):
        model = load_model(GO1, config.replace(floor_contacts=floor))
        data = mujoco.MjData(model)
        mujoco.mj_resetData(model, data)
        data.qpos[7:] = GO1.nominal_pose
        data.ctrl[:] = GO1.nominal_pose
        for _ in range(500):
            mujoco.mj_step(model, data)
        traces.append(data.qpos.copy())
    np.testing.assert_allclose(traces[0], traces[1], rtol=0, atol=1e-9)


def test_an_unknown_floor_contacts_value_is_one_line():
    message = "floor_contacts must be one of auto, all, feet, got 'legs'"
    with pytest.raises(ValueError, match=message):
        GO1.config_class().replace(floor_contacts="legs")


def test_a_quadruped_run_saved_before_the_field_keeps_every_geom():
    saved = TrainConfig.from_dict({"robot": "go1"}).to_dict()
    assert saved["env"].pop("floor_contacts") == "auto"  # a new run's
    assert TrainConfig.from_dict(saved).env.floor_contacts == "all"
    assert "floor_contacts" not in TrainConfig().to_dict()["env"]  # the hopper has none
    assert TrainConfig.from_dict(TrainConfig().to_dict()) == TrainConfig()
