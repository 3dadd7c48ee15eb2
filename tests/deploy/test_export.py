"""`cpg-actor export`: the exported control step (TorchScript, ONNX via onnxruntime) acts as
the PyTorch policy over a whole evaluation episode, carrying its CPG state; its metadata
describes the robot and the run; the MJCF next to it is the simulated model; a non-finite
observation gets a finite action; the checkpoint must be the run's; the exporters are quiet."""

import json
import logging
import warnings

import numpy as np
import pytest
import torch

import cpg_actor
from cpg_actor.cli import main
from cpg_actor.deploy import load_policy
from cpg_actor.deploy.export import OBSERVATION_SOURCES, export_policy, read_metadata, sidecar_paths
from cpg_actor.robots.common.actuator import Actuator
from cpg_actor.robots.common.mujoco_runtime import mujoco  # MUJOCO_GL chosen first
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.vector import HopperVectorEnv
from cpg_actor.robots.registry import get_robot
from tiny import trained_run  # tests/tiny.py (pytest puts tests/ on sys.path)


@pytest.fixture(scope="module")
def hopper_run(tmp_path_factory):
    return trained_run(tmp_path_factory.mktemp("hopper") / "run", "cpg-actor")


@pytest.fixture(scope="module")
def anymal_run(tmp_path_factory):
    return trained_run(tmp_path_factory.mktemp("anymal") / "run", "cpg-actor", "anymal")


def exported_step(path, fmt):
    if fmt == "torchscript":
        module = torch.jit.load(str(path))

        def step(obs, state):
            action, next_state = module(torch.as_tensor(obs), torch.as_tensor(state))
            return action.numpy(), next_state.numpy()

        return step
    ort = pytest.importorskip("onnxruntime")
    session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    return lambda obs, state: tuple(session.run(None, {"observation": obs, "state": state}))


@pytest.mark.parametrize(
    ("agent", "fmt"),
    [("cpg-actor", "torchscript"), ("cpg-actor", "onnx"), ("mlp", "onnx")],
)
def test_exported_policy_matches_the_pytorch_policy_over_an_episode(tmp_path, agent, fmt):
    if fmt == "onnx":
        pytest.importorskip("onnxscript")
    run_dir = trained_run(tmp_path / "run", agent)
    policy = load_policy(run_dir)
    path = export_policy(policy, tmp_path / f"policy.{fmt}", fmt)
    step = exported_step(path, fmt)
    state = np.load(path.with_name(path.name + ".initial_state.npy"))
    env = HopperVectorEnv(1, episode_steps=200)
    obs, _ = env.reset(seed=3)
    policy.reset(1)
    try:
        for _ in range(200):
            expected = policy.act(obs).action
            action, state = step(np.asarray(obs, dtype=np.float32), state)
            assert np.allclose(action, expected, atol=1e-5), (action, expected)
            assert np.allclose(state, policy.state.numpy(), atol=1e-5)
            obs, _, terminated, truncated, _ = env.step(expected)
            if terminated[0] or truncated[0]:
                break
    finally:
        env.close()
    with pytest.raises(FileExistsError, match="--overwrite"):
        export_policy(policy, path, fmt)


def test_export_refuses_what_it_cannot_deploy(tmp_path):
    run_dir = trained_run(tmp_path / "run", "cho2019")
    with pytest.raises(ValueError, match="only agents that output joint positions"):
        export_policy(load_policy(run_dir), tmp_path / "p.pt", "torchscript")
    with pytest.raises(ValueError, match="unknown export format 'tflite'"):
        export_policy(load_policy(run_dir), tmp_path / "p.tfl", "tflite")


def test_export_command_writes_the_file_and_says_what_it_takes(tmp_path, capsys, caplog):
    run_dir = trained_run(tmp_path / "run", "cpg-actor")
    for fmt, name in (("torchscript", "policy.pt"), ("onnx", "policy.onnx")):
        if fmt == "onnx":
            pytest.importorskip("onnxscript")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")  # every warning the exporters raise is recorded
            assert main(["export", str(run_dir), "--format", fmt]) == 0
        captured = capsys.readouterr()
        # only its own line: no tracer, deprecation or optimiser notes
        assert [str(w.message) for w in caught] == []
        assert [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING] == []
        assert captured.err == ""
        assert len(captured.out.splitlines()) == 1
        assert "observation (1, 8) and state (1, 5, 2)" in captured.out
        assert f"{name}.robot.xml" in captured.out
        for path in (name, f"{name}.initial_state.npy", f"{name}.robot.xml"):
            assert (run_dir / "export" / path).is_file()
    assert main(["export", str(run_dir), "--format", "torchscript"]) == 2
    assert "exists; pass --overwrite" in capsys.readouterr().err
    assert main(["export", str(tmp_path / "missing")]) == 2


def test_export_refuses_a_checkpoint_of_another_run(tmp_path, capsys):
    """As `cpg-actor eval`: the checkpoint must hold the run's agent, and the run must be one
    (its config.yaml); nothing is written otherwise."""
    run_dir = trained_run(tmp_path / "run", "cpg-actor")
    other = trained_run(tmp_path / "other", "mlp")
    checkpoint = other / "checkpoints" / "last.pt"
    for command in ("export", "eval"):
        assert main([command, str(run_dir), "--checkpoint", str(checkpoint)]) == 2
        err = capsys.readouterr().err
        assert "was trained with agent 'mlp', this run uses 'cpg-actor'" in err, err
        assert len(err.splitlines()) == 1
    assert not (run_dir / "export").exists()
    (other / "config.yaml").unlink()
    assert main(["export", str(other)]) == 2
    assert "config.yaml does not exist; is" in capsys.readouterr().err


@pytest.mark.parametrize("fmt", ["onnx", "torchscript"])
def test_a_nonfinite_observation_gets_the_action_of_the_normalisers_mean(hopper_run, tmp_path, fmt):
    """NaN and +-inf entries become the normaliser's mean (normalised 0) inside the model: the
    action and the next state are those of that observation, finite."""
    if fmt == "onnx":
        pytest.importorskip("onnxscript")
    policy = load_policy(hopper_run)
    path = export_policy(policy, tmp_path / f"policy.{fmt}", fmt)
    step = exported_step(path, fmt)
    state = np.load(sidecar_paths(path)["initial_state"])
    mean = policy.normalizer.mean.numpy().astype(np.float32)
    obs = np.array([[0.45, -0.85, 0.3, -0.2, 0.4, -0.8, 0.47, 0.05]], dtype=np.float32)
    broken = obs.copy()
    broken[0, [0, 3, 7]] = [np.nan, np.inf, -np.inf]
    repaired = broken.copy()
    repaired[0, [0, 3, 7]] = mean[[0, 3, 7]]
    action, next_state = step(broken, state)
    expected_action, expected_state = step(repaired, state)
    assert np.isfinite(action).all() and np.isfinite(next_state).all()
    np.testing.assert_array_equal(action, expected_action)
    np.testing.assert_array_equal(next_state, expected_state)
    assert not np.array_equal(step(obs, state)[0], action)  # the entries did matter
    assert "observation_normalization.mean" in read_metadata(path)["nonfinite_observations"]


@pytest.mark.parametrize("robot", ["hopper", "anymal"])
def test_metadata_describes_the_robot_the_run_and_the_state(hopper_run, anymal_run, tmp_path,
                                                            robot):  # fmt: skip
    pytest.importorskip("onnxscript")
    run = hopper_run if robot == "hopper" else anymal_run
    policy = load_policy(run)
    spec, env = policy.robot, policy.config.env
    onnx_path = export_policy(policy, tmp_path / "policy.onnx", "onnx")
    meta = read_metadata(onnx_path)
    assert meta["cpg_actor_version"] == cpg_actor.__version__
    assert (meta["robot"], meta["robot_model"], meta["agent"]) == (robot, spec.name, "cpg-actor")
    assert meta["joint_names"] == list(spec.joint_names)
    assert meta["default_joint_positions"] == list(spec.nominal_pose)
    assert meta["action_low"] == list(spec.action_low)
    assert meta["action_high"] == list(spec.action_high)
    assert meta["control_dt"] == pytest.approx(env.control_dt, rel=1e-12)
    assert meta["physics_dt"] * meta["decimation"] == pytest.approx(meta["control_dt"], rel=1e-12)
    assert meta["observation_names"] == list(spec.observation_names)
    sources = meta["observation_sources"]
    assert [entry["name"] for entry in sources] == meta["observation_names"]
    assert {entry["source"] for entry in sources} <= set(OBSERVATION_SOURCES)
    law = Actuator.from_config(env)
    assert meta["actuator"] == {
        "law": law.law, "kp": law.kp, "kd": law.kd, "torque_limit": law.torque_limit,
        "velocity_limit": law.velocity_limit, "saturation_torque": law.saturation_torque,
    }  # fmt: skip
    normalization = meta["observation_normalization"]
    assert normalization["inside"] is True
    assert np.allclose(normalization["mean"], policy.normalizer.mean.numpy(), rtol=1e-12)
    assert (meta["input_names"], meta["output_names"]) == (["observation", "state"],
                                                           ["action", "next_state"])  # fmt: skip
    initial = np.load(sidecar_paths(onnx_path)["initial_state"])
    assert meta["state_shape"] == list(initial.shape) == [1, *policy.agent.state_shape]
    np.testing.assert_array_equal(np.asarray(meta["initial_state"], dtype=np.float32), initial)
    rows = ["phase", "phase_velocity", "amplitude", "amplitude_velocity",
            "amplitude_acceleration"] + (["drive"] if robot == "anymal" else [])  # fmt: skip
    assert meta["state_rows"] == rows
    assert meta["drive_observation"] == spec.drive_observation
    assert meta["env_config"]["decimation"] == env.decimation
    assert meta["mjcf_file"] == "policy.onnx.robot.xml"
    # the TorchScript archive carries the same metadata (its own file names aside)
    script = read_metadata(export_policy(policy, tmp_path / "policy.pt", "torchscript"))
    assert script["mjcf_file"] == "policy.pt.robot.xml"
    assert {**script, "mjcf_file": ""} == {**meta, "mjcf_file": ""}
    files = {"metadata.json": ""}
    torch.jit.load(str(tmp_path / "policy.pt"), _extra_files=files)
    assert json.loads(files["metadata.json"])["robot"] == robot


def model_bytes(model):
    buffer = np.zeros(mujoco.mj_sizeModel(model), dtype=np.uint8)
    mujoco.mj_saveModel(model, None, buffer)
    return buffer.tobytes()


@pytest.mark.parametrize(
    "config",
    [
        HopperConfig(),
        HopperConfig(physics_dt=0.0007, foot_friction=0.63, kp=91.3, actuator_law="coast"),
        QuadrupedConfig(),
        QuadrupedConfig(physics_dt=0.0013, foot_friction=0.55, kd=3.1, torque_limit=33.3),
    ],
)
def test_the_exported_mjcf_is_the_model_the_env_simulates(config):
    """Loaded, the MJCF written next to an export equals the env's MjModel in every byte (the
    configured actuators, timestep, friction; the coast law's actuators switched off)."""
    name = "hopper" if isinstance(config, HopperConfig) else "anymal"
    env = get_robot(name).make(1, config, 1)
    try:
        simulated = env.sim.backend.model if name == "hopper" else env.model
        loaded = mujoco.MjModel.from_xml_string(get_robot(name).mjcf(config))
        assert model_bytes(loaded) == model_bytes(simulated)
    finally:
        env.close()


def test_exported_quadruped_policy_reads_its_drive_from_the_raw_command(tmp_path):
    """On the quadruped the exported step sets the CPG's drive from the raw observation (the
    forward-speed command) as the policy does: same actions and states, drive row included."""
    from cpg_actor.robots.anymal.vector import AnymalVectorEnv

    trained_run(tmp_path / "run", "cpg-actor", "anymal", env={"episode_seconds": 0.2})
    policy = load_policy(tmp_path / "run")
    path = export_policy(policy, tmp_path / "policy.pt", "torchscript")
    step = exported_step(path, "torchscript")
    state = np.load(path.with_name(path.name + ".initial_state.npy"))
    env = AnymalVectorEnv(1, {"command_range": (0.8, 0.8)})
    obs, _ = env.reset(seed=1)
    policy.reset(1)
    try:
        for _ in range(20):
            expected = policy.act(obs).action
            action, state = step(np.asarray(obs, dtype=np.float32), state)
            assert np.allclose(action, expected, atol=1e-5)
            assert np.allclose(state, policy.state.numpy(), atol=1e-5)
            obs = env.step(expected)[0]
        assert np.allclose(state[0, 5], 0.8)  # the drive row: d = the command
    finally:
        env.close()
