"""The Unitree Go1: its generated MJCF (mass, joints in order with their ranges, torque limits,
the actuator law's per-joint constants), the registry entry, the config, standing at the
nominal pose, the trot and walk presets' phase pattern, and Gymnasium's checker."""

import math

import gymnasium as gym
import numpy as np
import pytest
import torch
from gymnasium.utils.env_checker import check_env

import cpg_actor  # noqa: F401  (registers the Gymnasium ids)
from cpg_actor.config import TrainConfig, apply_dict, parse_override
from cpg_actor.robots.common.actuator import Actuator
from cpg_actor.robots.common.mujoco_runtime import mujoco
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.common.quadruped.gaits import GAITS
from cpg_actor.robots.go1 import description as robot
from cpg_actor.robots.go1.config import Go1Config
from cpg_actor.robots.go1.env import Go1Env
from cpg_actor.robots.go1.gaits import GO1_GAITS
from cpg_actor.robots.go1.mjcf import mjcf_text
from cpg_actor.robots.go1.plugin import ENV_ID
from cpg_actor.robots.go1.vector import Go1VectorEnv
from cpg_actor.robots.registry import ROBOTS, get_robot, robot_of_config

ORDER = tuple(f"{leg}_{kind}_joint" for leg in ("FR", "FL", "RR", "RL")
              for kind in ("hip", "thigh", "calf"))  # fmt: skip
RANGES = {"hip": (-0.863, 0.863), "thigh": (-0.686, 4.501), "calf": (-2.818, -0.888)}
LIMITS = {"hip": 23.7, "thigh": 23.7, "calf": 35.55}


@pytest.fixture(scope="module")
def model():
    return mujoco.MjModel.from_xml_string(mjcf_text())


def test_the_mjcf_has_the_go1s_mass_joints_and_ranges(model):
    assert model.body_subtreemass[model.body("trunk").id] == pytest.approx(12.743, rel=1e-3)
    assert robot.TOTAL_MASS == pytest.approx(12.743, rel=1e-3)
    hinges = [model.joint(j).name for j in range(model.njnt)
              if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE]  # fmt: skip
    assert tuple(hinges) == ORDER == robot.JOINT_NAMES
    assert model.nu == 12
    assert tuple(model.joint(model.actuator_trnid[i, 0]).name for i in range(12)) == ORDER
    for name in ORDER:
        assert tuple(model.joint(name).range) == pytest.approx(RANGES[name.split("_")[1]])
    assert model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC and model.opt.impratio == 100
    foot = model.geom("FR_foot")
    assert foot.condim == 6 and foot.friction[0] == pytest.approx(0.8)
    assert tuple(foot.solimp[:3]) == pytest.approx((0.015, 1.0, 0.031))
    # only primitives, and nothing of the robot collides with itself
    assert set(model.geom_type) <= {int(t) for t in (mujoco.mjtGeom.mjGEOM_PLANE,
        mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_CYLINDER, mujoco.mjtGeom.mjGEOM_CAPSULE,
        mujoco.mjtGeom.mjGEOM_SPHERE)}  # fmt: skip
    robot_geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] != 0]
    assert all(model.geom_contype[g] == 0 for g in robot_geoms)


def test_the_drives_are_clipped_at_the_go1s_torque_limits(model):
    """Far from its target at rest, each drive gives its torque limit, 23.7, 23.7, 35.55 N m;
    the numpy law agrees, per joint."""
    data = mujoco.MjData(model)
    data.qpos[2] = 0.5
    data.qpos[7:] = robot.NOMINAL_POSE
    for sign in (1.0, -1.0):
        data.ctrl[:] = np.asarray(robot.NOMINAL_POSE) + sign * 0.5
        mujoco.mj_forward(model, data)
        expected = [sign * LIMITS[name.split("_")[1]] for name in ORDER]
        assert data.actuator_force == pytest.approx(expected)
        law = Actuator.from_config(Go1Config())(data.ctrl[None], data.qpos[None, 7:],
                                                np.zeros((1, 12)))  # fmt: skip
        assert law[0] == pytest.approx(expected)
    # the speed limit: at the knee's no-load speed, no torque in the direction of motion
    law = Actuator.from_config(Go1Config())
    lower, upper = law.torque_bounds(np.array([[0.0, 0.0, 20.06] * 4]))
    assert upper[0, 2] == pytest.approx(0.0, abs=1e-9) and lower[0, 2] == -35.55


@pytest.mark.parametrize(
    "config", [Go1Config(), Go1Config(physics_dt=0.0013, foot_friction=0.55, kd=(1.0, 2.0, 3.0))]
)
def test_the_exported_mjcf_is_the_model_the_env_simulates(config):
    """Loaded, the MJCF `cpg-actor export` writes equals the env's MjModel in every byte."""
    env = get_robot("go1").make(1, config, 1)
    loaded = mujoco.MjModel.from_xml_string(get_robot("go1").mjcf(config))
    saved = []
    for model in (loaded, env.model):
        buffer = np.zeros(mujoco.mj_sizeModel(model), dtype=np.uint8)
        mujoco.mj_saveModel(model, None, buffer)
        saved.append(buffer.tobytes())
    assert saved[0] == saved[1]
    env.close()


def test_the_registry_lists_the_go1_and_tells_its_config_from_anymals():
    assert "go1" in ROBOTS and get_robot("go1").config_class is Go1Config
    assert robot_of_config(Go1Config()).name == "go1"
    assert robot_of_config(QuadrupedConfig()).name == "anymal"
    assert {g.id for g in get_robot("go1").gym_ids} == {ENV_ID, "cpg_actor/Go1-mjx-v0"}
    layouts = get_robot("go1").cpg_layouts()
    assert set(layouts) == {"joint", "leg"} and next(iter(layouts["joint"].gaits)) == "trot"
    config = TrainConfig()
    apply_dict(config, parse_override("robot=go1"), "")
    apply_dict(config, parse_override("env.torque_limit=[20, 20, 30]"), "")
    assert isinstance(config.env, Go1Config) and config.env.torque_limit == (20, 20, 30)
    config.validate()
    again = TrainConfig.from_dict(config.to_dict())
    assert type(again.env) is Go1Config and again.env == config.env
    apply_dict(config, parse_override("robot=anymal"), "")  # back to ANYmal's config
    assert type(config.env) is QuadrupedConfig


def test_the_config_keeps_its_own_defaults_and_checks_per_joint_constants():
    config = Go1Config.from_dict({"reward_scales": {"feet_slip": -0.1}})
    assert config.reward_scales["torques"] == -2e-4 and config.reward_scales["feet_slip"] == -0.1
    assert Go1Config().torque_limit == (23.7, 23.7, 35.55)
    with pytest.raises(ValueError, match="torque_limit must be a finite number > 0 or three"):
        Go1Config(torque_limit=(1.0, 2.0)).validate()
    with pytest.raises(ValueError, match="config must be a Go1Config"):
        Go1VectorEnv(1, QuadrupedConfig())


def test_it_stands_at_the_nominal_pose():
    """PD on the nominal pose for 2 s: no fall, the trunk level at about 0.27 m."""
    env = Go1VectorEnv(2, {"reset_noise": 0.0, "command_range": (0.0, 0.0)})
    env.reset(seed=0)
    actions = np.tile(robot.NOMINAL_POSE, (2, 1))
    for _ in range(100):
        _, _, terminated, truncated, info = env.step(actions)
        assert not terminated.any() and not truncated.any()
    assert info["base_height"] == pytest.approx(0.27, abs=0.01)
    assert np.abs(env.qpos[:, 7:] - actions).max() < 0.1
    assert info["contact"].all()
    env.close()


def test_the_gait_presets_phase_the_legs_by_their_place():
    """FR, FL, RR, RL are the right front, left front, right hind and left hind legs: their
    hip oscillators start at those places' phases, each knee a quarter cycle ahead."""
    for gait in ("trot", "walk"):
        phases = np.array(GO1_GAITS.gait_phases(gait))
        places = {"FR": "RF", "FL": "LF", "RR": "RH", "RL": "LH"}
        expected = [2 * math.pi * GAITS[gait][("LF", "RF", "LH", "RH").index(places[leg])]
                    for leg in ("FR", "FL", "RR", "RL")]  # fmt: skip
        assert phases[0::2] == pytest.approx(expected)
        assert phases[1::2] - phases[0::2] == pytest.approx([math.pi / 2] * 4)
        cpg = GO1_GAITS.leg_cpg(0.02, gait)
        assert cpg.initial_state(1).phase[0].tolist() == pytest.approx(expected)


def test_the_open_loop_trot_moves_diagonal_feet_together():
    """The trot preset open loop (the drive of 0.5 m/s): the robot walks forward without a
    fall, the diagonal feet (FR with RL, FL with RR) touch down together, the lateral pairs
    alternate."""
    env = Go1VectorEnv(1, {"reset_noise": 0.0, "command_range": (0.5, 0.5)})
    env.reset(seed=0)
    actions = GO1_GAITS.open_loop_positions("trot", 0.02, robot.NOMINAL_POSE, 1, 150, 0.5)
    contacts, x0 = [], env.qpos[0, 0]
    for action in actions.numpy():
        _, _, terminated, _, info = env.step(action)
        assert not terminated.any()
        contacts.append(info["contact"][0])
    contact = np.array(contacts[25:], dtype=float)  # past the first steps
    corr = np.corrcoef(contact.T)
    assert corr[0, 3] > 0.3 and corr[1, 2] > 0.3  # FR-RL, FL-RR
    assert corr[0, 1] < -0.2 and corr[2, 3] < -0.2  # FR-FL, RR-RL
    assert env.qpos[0, 0] - x0 > 0.5  # 3 s forward
    env.close()


def test_the_foot_space_pattern_holds_the_nominal_pose_at_zero_amplitude():
    pattern = GO1_GAITS.foot_space(robot.NOMINAL_POSE).double()
    phase = torch.full((1, 4), math.pi)  # mid stance: dz = 0
    joints = pattern(phase.double(), torch.zeros(1, 4, dtype=torch.float64))
    assert joints[0].tolist() == pytest.approx(robot.NOMINAL_POSE, abs=1e-6)


def test_gymnasium_checker_passes_on_the_single_env_id():
    env = gym.make(ENV_ID)
    assert isinstance(env.unwrapped, Go1Env)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()
    vec = gym.make_vec(ENV_ID, num_envs=2)
    assert isinstance(vec.unwrapped, Go1VectorEnv) and vec.observation_space.shape == (2, 45)
    vec.close()
