"""The one robot description: shipped MJCF and URDF are generated from it and load identically."""

from __future__ import annotations

import numpy as np
import pytest

from cpg_actor.robots.anymal_leg import kinematics as leg_kinematics
from cpg_actor.robots.assets import stale_assets
from cpg_actor.robots.common.actuator import Actuator
from cpg_actor.robots.common.mujoco_runtime import mujoco  # MUJOCO_GL chosen first
from cpg_actor.robots.hopper import description as robot
from cpg_actor.robots.hopper import kinematics
from cpg_actor.robots.hopper.backends import make_backend
from cpg_actor.robots.hopper.backends.mujoco_backend import load_model
from cpg_actor.robots.hopper.backends.pybullet_backend import FOOT_LINK
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.mjcf import mjcf_text

LINKS = ("hip", "thigh", "shank", "adapter")  # PyBullet link index = position here
POSES = [(0.4, -0.8), (0.0, 0.0), (1.2, -1.6), (-0.4, 0.05)]


@pytest.fixture(scope="module")
def mj():
    backend = make_backend(HopperConfig(sim="mujoco"))
    yield backend.model
    backend.close()


@pytest.fixture(scope="module")
def pb():
    backend = make_backend(HopperConfig(sim="pybullet"))
    yield backend.handle(0)
    backend.close()


def test_shipped_files_are_generated_from_the_description():
    assert stale_assets() == [], "run `python -m cpg_actor.robots` to regenerate"


def test_total_moving_mass_is_the_paper_s():
    assert robot.TOTAL_MASS == pytest.approx(3.407, abs=1e-3)
    assert robot.TOTAL_MASS == pytest.approx(3.42, rel=0.01)  # paper: 3.42 kg


def test_masses_coms_and_inertias_agree(mj, pb):
    client, body = pb
    for index, name in enumerate(LINKS):
        link = robot.LINKS[name]
        mj_id = mj.body(name).id
        assert mj.body_mass[mj_id] == pytest.approx(link.mass, abs=1e-9)
        np.testing.assert_allclose(mj.body_ipos[mj_id], link.com, atol=1e-9)
        np.testing.assert_allclose(mj.body_inertia[mj_id], link.inertia, rtol=1e-6)
        np.testing.assert_allclose(mj.body_iquat[mj_id], [1, 0, 0, 0], atol=1e-9)
        info = client.getDynamicsInfo(body, index)
        assert info[0] == pytest.approx(link.mass, abs=1e-9)
        np.testing.assert_allclose(info[2], link.inertia, rtol=1e-6)
        np.testing.assert_allclose(info[3], link.com, atol=1e-9)
        np.testing.assert_allclose(info[4], [0, 0, 0, 1], atol=1e-9)


def test_joint_types_axes_and_limits_agree(mj, pb):
    client, body = pb
    for index, joint in enumerate(robot.JOINTS[:3]):
        mj_joint = mj.joint(joint.name)
        info = client.getJointInfo(body, index)
        assert info[1].decode() == joint.name
        assert info[2] == {"prismatic": 1, "revolute": 0}[joint.kind]
        assert mj_joint.type[0] == {"prismatic": 2, "revolute": 3}[joint.kind]
        np.testing.assert_allclose(mj_joint.axis, joint.axis)
        np.testing.assert_allclose(info[13], joint.axis)
        np.testing.assert_allclose(mj_joint.range, joint.limits)
        np.testing.assert_allclose((info[8], info[9]), joint.limits)
    assert robot.JOINT_LIMITS["HFE"][0] < robot.NOMINAL_POSE[0] < robot.JOINT_LIMITS["HFE"][1]
    assert robot.JOINT_LIMITS["KFE"][0] < robot.NOMINAL_POSE[1] < robot.JOINT_LIMITS["KFE"][1]


def test_foot_contact_geometry_agrees(mj, pb):
    client, body = pb
    foot = mj.geom("foot")
    assert foot.size[0] == pytest.approx(0.031)
    np.testing.assert_allclose(foot.pos, robot.FOOT_CENTER)
    # one explicit foot-ground pair, and no geom that collides on its own
    assert mj.npair == 1
    assert {mj.pair_geom1[0], mj.pair_geom2[0]} == {foot.id, mj.geom("ground").id}
    np.testing.assert_allclose(mj.pair_friction[0, :2], 0.8)
    assert not mj.geom_contype.any() and not mj.geom_conaffinity.any()
    shapes = client.getCollisionShapeData(body, FOOT_LINK)
    assert len(shapes) == 1
    assert shapes[0][3][0] == pytest.approx(0.031)  # sphere radius
    assert client.getDynamicsInfo(body, FOOT_LINK)[1] == pytest.approx(0.8)  # lateral friction
    for link in range(FOOT_LINK):  # only the foot collides
        assert client.getCollisionShapeData(body, link) == ()


def _collision_detected_hopper(friction: float) -> mujoco.MjModel:
    """The hopper as it was before the explicit pair: the foot (its class: contype 1, solref
    0.005) and the ground collide by collision detection, the contact mixing their parameters."""
    text = mjcf_text(Actuator.from_config(HopperConfig()))
    start, end = text.index("  <contact>"), text.index("</contact>") + len("</contact>\n")
    text = text[:start] + text[end:]
    text = text.replace(' contype="0" conaffinity="0"/>', "/>")
    text = text.replace(
        'material="grid"/>', 'material="grid" contype="1" conaffinity="1" condim="3"/>'
    )
    model = mujoco.MjModel.from_xml_string(text)
    model.opt.timestep = 0.001
    model.geom_friction[[model.geom("foot").id, model.geom("ground").id], 0] = friction
    return model


@pytest.mark.parametrize("friction", [0.8, 0.3])
def test_the_explicit_pair_is_the_contact_collision_detection_makes(friction):
    """Same states, bit for bit, through drops, landings and slips with and without the pair
    (the pair only spares MuJoCo its broad phase)."""
    config = HopperConfig(foot_friction=friction)
    models = {
        "pair": load_model(config.physics_dt, friction, Actuator.from_config(config)),
        "detected": _collision_detected_hopper(friction),
    }
    rng = np.random.default_rng(0)
    nominal = np.array(robot.NOMINAL_POSE)
    desired = rng.uniform(nominal - 0.6, nominal + 0.3, (40, 2))
    trajectories = {}
    for name, model in models.items():
        data = mujoco.MjData(model)
        data.qpos[:] = [0.5, *robot.NOMINAL_POSE]  # dropped from 0.5 m
        states, contacts = [], 0
        for target in desired:
            data.ctrl[:] = target
            for _ in range(20):
                mujoco.mj_step(model, data)
                contacts += data.ncon
            states.append(np.concatenate([data.qpos, data.qvel, data.sensordata]))
        assert contacts > 100  # the foot did land
        trajectories[name] = np.array(states)
    np.testing.assert_array_equal(trajectories["pair"], trajectories["detected"])


@pytest.mark.parametrize("pose", POSES)
def test_link_frames_and_coms_agree_in_every_pose(mj, pb, pose):
    """World frames and COMs of all links (this checks every joint frame) and the foot."""
    client, body = pb
    data = mujoco.MjData(mj)
    data.qpos[:] = (0.7, *pose)
    mujoco.mj_kinematics(mj, data)
    client.resetJointState(body, 0, 0.7)
    client.resetJointState(body, 1, pose[0])
    client.resetJointState(body, 2, pose[1])
    for index, name in enumerate(LINKS):
        state = client.getLinkState(body, index, computeForwardKinematics=1)
        np.testing.assert_allclose(state[4], data.xpos[mj.body(name).id], atol=1e-7)
        np.testing.assert_allclose(state[0], data.xipos[mj.body(name).id], atol=1e-7)
    # and the hand-written planar kinematics (x, z relative to the hip)
    foot = leg_kinematics.foot_position(np.array(pose))
    site = data.site_xpos[mj.site("foot").id]
    np.testing.assert_allclose([site[0], site[2] - 0.7], foot, atol=1e-9)
    knee = leg_kinematics.knee_position(np.array(pose))
    anchor = data.xanchor[mj.joint("KFE").id]
    np.testing.assert_allclose([anchor[0], anchor[2] - 0.7], knee, atol=1e-9)
    for name, (x, z) in kinematics.com_positions(pose).items():
        com = data.xipos[mj.body(name).id]
        np.testing.assert_allclose([com[0], com[2] - 0.7], [x, z], atol=1e-9)


def test_nominal_pose_puts_the_foot_under_the_hip_with_the_knee_bent():
    hfe_x = leg_kinematics.HFE_ORIGIN[0]
    foot = leg_kinematics.foot_position(np.array(robot.NOMINAL_POSE))
    knee = leg_kinematics.knee_position(np.array(robot.NOMINAL_POSE))
    lean = np.degrees(np.arctan2(foot[0] - hfe_x, -foot[1]))
    assert 0.0 < lean < 20.0  # foot slightly in front of the hip, 0.47 m below it
    assert -0.48 < foot[1] < -0.45
    assert knee[0] < hfe_x and knee[0] < foot[0]  # knee points backwards: bent
    # positive HFE swings the leg backwards (the sign convention in description.py)
    assert leg_kinematics.foot_position(np.array([0.6, -0.8]))[0] < foot[0]


def test_shipped_mjcf_has_the_default_actuators():
    """The backend writes the configured actuator constants; with the default config its model
    is the shipped file's, and other constants do reach the model."""
    config = HopperConfig()
    shipped = load_model(config.physics_dt, config.foot_friction)
    built = load_model(config.physics_dt, config.foot_friction, Actuator.from_config(config))
    for field in ("actuator_gainprm", "actuator_biasprm", "actuator_dynprm", "actuator_forcerange"):
        np.testing.assert_array_equal(getattr(shipped, field), getattr(built, field), err_msg=field)
    assert shipped.nu == 2 and shipped.na == 0 and shipped.nsensordata == 2
    other = load_model(0.001, 0.8, Actuator.from_config(HopperConfig(torque_limit=30.0)))
    np.testing.assert_array_equal(other.actuator_forcerange, [[-30.0, 30.0]] * 2)
