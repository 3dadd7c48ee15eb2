"""examples/deploy_onnx.py --mjcf OTHER.xml: an exported Go1 policy run on another model of
the Go1 (robots/go1/variant.py: other passive damping, armature, contact softness and
friction, its legs in another order, none of the project's sensors): joints found by name,
the actuator law applied as torques, sites, sensors and ground added where the file lacks
them; a file without the policy's joints refused in one line."""

import runpy
import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np
import pytest

from cpg_actor.config import TrainConfig
from cpg_actor.deploy import load_policy
from cpg_actor.deploy.export import export_policy, read_metadata
from cpg_actor.robots.go1.mjcf import MJCF_PATH
from cpg_actor.robots.go1.variant import ARMATURE, VARIANT_PATH, variant_mjcf
from tiny import trained_run  # tests/tiny.py

pytest.importorskip("onnxruntime")
pytest.importorskip("onnxscript")

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "deploy_onnx.py"


@pytest.fixture(scope="module")
def go1_policy(tmp_path_factory) -> Path:
    """An untrained (tiny-run) Go1 CPG-Actor, exported to ONNX."""
    path = tmp_path_factory.mktemp("go1")
    config = TrainConfig.load(trained_run(path / "run", "cpg-actor", "go1") / "config.yaml")
    policy = load_policy(path / "run", run_config=config)
    return export_policy(policy, path / "export" / "policy.onnx", "onnx")


@pytest.fixture(scope="module")
def example():
    return runpy.run_path(str(EXAMPLE))


def test_the_variant_is_the_same_go1_with_other_physics():
    assert VARIANT_PATH.read_text() == variant_mjcf()  # `python -m cpg_actor.robots` wrote it
    own = mujoco.MjModel.from_xml_path(str(MJCF_PATH))
    other = mujoco.MjModel.from_xml_path(str(VARIANT_PATH))
    assert other.nu == 0 and other.nsensor == 0  # none of the project's actuators, sensors
    assert sum(other.body_mass) == pytest.approx(sum(own.body_mass), rel=1e-12)
    own_names = [own.joint(j).name for j in range(own.njnt)]
    other_names = [other.joint(j).name for j in range(other.njnt)]
    assert sorted(own_names) == sorted(other_names) and own_names != other_names
    for name in own_names[1:]:
        a, b = own.joint(name), other.joint(name)
        assert own.dof_damping[a.dofadr[0]] > 0 and other.dof_damping[b.dofadr[0]] == 0
        assert other.dof_armature[b.dofadr[0]] == pytest.approx(
            ARMATURE[name.split("_")[1]], rel=1e-5
        )
        assert own.dof_armature[a.dofadr[0]] != other.dof_armature[b.dofadr[0]]
    foot = other.geom("FL_foot")
    assert foot.friction[0] == 0.6 and own.geom("FL_foot").friction[0] == 0.8
    assert not np.allclose(foot.solimp, own.geom("FL_foot").solimp)


def test_the_export_names_the_joints_sites_and_sensors(go1_policy):
    meta = read_metadata(go1_policy)
    assert meta["joint_names"][:3] == ["FR_hip_joint", "FR_thigh_joint", "FR_calf_joint"]
    interface = meta["model_interface"]
    assert interface["free_joint"] == "trunk" and interface["base_body"] == "trunk"
    assert {s["name"] for s in interface["sensors"]} >= {
        "base_ang_vel",
        "base_lin_vel",
        "FR_foot_pos",
        "base_touch",
    }
    joint_pos = [e for e in meta["observation_sources"] if e["source"] == "qpos"]
    assert [e["joint"] for e in joint_pos] == meta["joint_names"]
    assert all(e["element"] == 0 for e in joint_pos)


def test_the_policy_runs_on_the_other_model_its_joints_mapped_by_name(go1_policy, example):
    meta = example["Policy"](go1_policy).meta
    own = example["Simulation"](meta, go1_policy.with_name(meta["mjcf_file"]))
    other = example["Simulation"](meta, VARIANT_PATH, other=True)
    assert other.torque_law  # the file's own timestep, the policy's control period
    period = own.decimation * own.model.opt.timestep
    assert other.decimation * other.model.opt.timestep == pytest.approx(period, rel=1e-9)
    # the same joint, wherever the file puts it
    for j, name in enumerate(meta["joint_names"]):
        assert other.qpos_index[j] == other.model.joint(name).qposadr[0]
    assert not np.array_equal(other.qpos_index, own.qpos_index)
    assert other.legs == own.legs  # the foot sensors added, in the policy's order
    own.reset(7)
    other.reset(7)
    # the same start, read the same way: the observations agree entry by entry
    np.testing.assert_allclose(other.observation(), own.observation(), rtol=1e-9, atol=1e-9)
    for sim in (own, other):
        for _ in range(3):
            reward, terminated, _ = sim.step(np.asarray(meta["default_joint_positions"]))
            assert np.isfinite(reward) and not terminated
    # the drives pull each joint towards its own command: the knee asked to bend bends
    knee = meta["joint_names"].index("RL_calf_joint")
    poses = []
    for bend in (0.0, 0.3):
        other.reset(7)
        desired = np.asarray(meta["default_joint_positions"]).copy()
        desired[knee] -= bend
        for _ in range(5):
            other.step(desired)
        poses.append(other.data.qpos[other.qpos_index].copy())
    moved = poses[1] - poses[0]
    assert moved[knee] < -0.2 and np.abs(np.delete(moved, knee)).max() < 0.5 * abs(moved[knee])


def test_the_example_runs_the_other_model_with_a_command(go1_policy, example, capsys):
    assert example["main"]([str(go1_policy), "--mjcf", str(VARIANT_PATH), "--steps", "5",
                            "--command", "0.5"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "over 5 steps (step limit)" in out and "command 0.5 m/s: mean forward speed" in out


def test_a_file_without_floor_or_imu_gets_them(go1_policy, example, tmp_path):
    root = ET.fromstring(VARIANT_PATH.read_text())
    world = root.find("worldbody")
    world.remove(world.find("geom"))  # no ground
    trunk = world.find("body")
    trunk.remove(trunk.find("site"))  # no IMU
    bare = tmp_path / "bare.xml"
    bare.write_text(ET.tostring(root, encoding="unicode"))
    meta = example["Policy"](go1_policy).meta
    sim = example["Simulation"](meta, bare, other=True)
    assert sim.model.geom("ground").type[0] == mujoco.mjtGeom.mjGEOM_PLANE
    assert sim.model.site("imu").bodyid[0] == sim.model.body("trunk").id
    sim.reset(3)
    _, terminated, _ = sim.step(np.asarray(meta["default_joint_positions"]))
    assert not terminated  # standing on the added ground


def test_a_model_without_the_policys_joints_is_refused_in_one_line(
    go1_policy, example, tmp_path, capsys
):
    text = VARIANT_PATH.read_text().replace('"RR_calf_joint"', '"RR_knee"')
    text = text.replace('"FL_hip_joint"', '"FL_abduction"')
    other = tmp_path / "renamed.xml"
    other.write_text(text)
    assert example["main"]([str(go1_policy), "--mjcf", str(other), "--steps", "2"]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1, err
    assert "lacks the policy's joints FL_hip_joint, RR_calf_joint" in err
