"""`cpg-actor export` of runs trained with the field's recipes: the Go1's MuJoCo Playground
recipe (the base's linear velocity in the observation, a privileged critic, the running
normaliser) and ANYmal B's legged_gym recipe (the linear velocity, fixed observation scales,
no normaliser). The exported step takes the actor's observation alone and acts as the trained
policy's mean on it; ``Policy.act`` takes it too; the metadata describes every entry, the
linear velocity's source included; a run the interface cannot describe is refused in one
line."""

import numpy as np
import pytest

from cpg_actor.agents.base import observation_scale
from cpg_actor.cli import main
from cpg_actor.config.presets import LEGGED_GYM_OBSERVATION_SCALES as OBSERVATION_SCALES
from cpg_actor.deploy import load_policy
from cpg_actor.deploy.export import OBSERVATION_SOURCES, export_policy, read_metadata
from cpg_actor.robots.registry import get_robot
from cpg_actor.tasks import velocity as task
from cpg_actor.training.build import make_env

RECIPES = {"playground": "go1", "legged_gym": "anymal"}


def recipe_run(path, preset: str, agent: str = "mlp", *extra: str):
    """A tiny run of ``agent`` under the recipe (two PPO iterations of 4 envs, 1 s episodes)."""
    code = main(["train", "--robot", RECIPES[preset], "--agent", agent, "--preset", preset,
                 "--total-steps", "192", "--num-envs", "4", "--seed", "3",
                 "--run-dir", str(path), "--no-progress", "--set", "ppo.compile=false",
                 "--set", "eval_interval=0", "--set", "env.episode_seconds=1.0",
                 *extra])  # fmt: skip
    assert code in (0, None)
    return path


@pytest.fixture(scope="module", params=list(RECIPES))
def run(request, tmp_path_factory):
    return request.param, recipe_run(tmp_path_factory.mktemp(request.param) / "run", request.param)


def observations(policy, steps: int = 12) -> np.ndarray:
    """The run's env's observations (privileged entries included) under the policy, (T, D)."""
    env = make_env(policy.config, get_robot(policy.config.robot), 1, 1)
    obs, _ = env.reset(seed=5)
    policy.reset(1)
    seen = []
    try:
        for _ in range(steps):
            seen.append(np.asarray(obs, dtype=np.float32))
            obs = env.step(policy.act(obs).action)[0]
    finally:
        env.close()
    return np.concatenate(seen)


def exported_step(path, fmt):
    if fmt == "torchscript":
        import torch

        module = torch.jit.load(str(path))
        return lambda obs, state: [t.numpy() for t in module(torch.as_tensor(obs),
                                                             torch.as_tensor(state))]  # fmt: skip
    ort = pytest.importorskip("onnxruntime")
    session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    return lambda obs, state: session.run(None, {"observation": obs, "state": state})


@pytest.mark.parametrize("fmt", ["torchscript", "onnx"])
def test_the_exported_step_acts_as_the_policys_mean_on_the_actors_observation(run, tmp_path,
                                                                              fmt):  # fmt: skip
    if fmt == "onnx":
        pytest.importorskip("onnxscript")
    preset, run_dir = run
    policy = load_policy(run_dir)
    size = policy.actor_obs_dim
    privileged = preset == "playground"
    assert (size < policy.obs_dim) == privileged  # the critic's entries come last
    path = export_policy(policy, tmp_path / f"policy.{fmt}", fmt)
    step = exported_step(path, fmt)
    state = np.zeros((1, 0), dtype=np.float32)
    nominal = np.asarray(policy.robot.nominal_pose, dtype=np.float32)
    policy.reset(1)
    for obs in observations(policy):
        full = policy.act(obs[None])
        actor = policy.act(obs[None, :size])  # a robot's observation: no privileged entries
        np.testing.assert_array_equal(actor.action, full.action)
        assert np.isfinite(full.agent.value.numpy()).all()
        assert np.isnan(actor.agent.value.numpy()).all() == privileged
        action, state = step(obs[None, :size], state)
        offset, expected = action - nominal, full.action - nominal  # off the standing pose
        assert np.abs(expected).max() > 1e-4
        np.testing.assert_allclose(offset, expected, rtol=1e-4, atol=1e-7)
    with pytest.raises(ValueError, match=rf"obs must have shape \(1, {size}\)"):
        policy.act(obs[None, : size - 1])
    if privileged:
        with pytest.raises(ValueError, match="update_normalizer needs the whole observation"):
            policy.act(obs[None, :size], update_normalizer=True)


def test_the_metadata_describes_every_entry_the_actor_reads(run, tmp_path):
    preset, run_dir = run
    policy = load_policy(run_dir)
    meta = read_metadata(export_policy(policy, tmp_path / "policy.pt", "torchscript"))
    names = meta["observation_names"]
    assert names == list(policy.robot.observation_names[: policy.actor_obs_dim])
    assert not any(name.startswith(task.PRIVILEGED_PREFIX) for name in names)
    assert names[-3:] == list(task.LIN_VEL_NAMES)
    sources = meta["observation_sources"]
    assert [entry["name"] for entry in sources] == names
    assert {entry["source"] for entry in sources} <= set(OBSERVATION_SOURCES)
    lin_vel = sources[-3:]
    assert [(e["source"], e["sensor"], e["index"]) for e in lin_vel] == [
        ("sensor", "base_lin_vel", i) for i in range(3)]  # fmt: skip
    assert all("state estimator" in entry["on_robot"] for entry in lin_vel)
    assert not any("on_robot" in entry for entry in sources[:-3])
    # the sensor is the base frame's velocimeter, on the base's IMU site
    sensor = next(s for s in meta["model_interface"]["sensors"] if s["name"] == "base_lin_vel")
    assert (sensor["type"], sensor["objname"]) == ("mjSENS_VELOCIMETER", "imu")
    # every transform of the observation is inside the model and described here
    normalization, scales = meta["observation_normalization"], meta["observation_scales"]
    assert normalization["inside"] is (preset == "playground")
    assert len(normalization["mean"]) == len(normalization["std"]) == len(names)
    assert scales["inside"] is True
    if preset == "legged_gym":
        assert scales["factors"] == observation_scale(names, OBSERVATION_SCALES)
        assert scales["factors"][-3:] == [2.0] * 3  # legged_gym's lin_vel scale
    else:
        assert scales["factors"] == [1.0] * len(names)


def test_a_run_whose_observation_the_interface_cannot_describe_is_refused_in_one_line(
    run, tmp_path, monkeypatch, capsys
):
    preset, run_dir = run
    described = task.observation_sources
    # a robot whose deploy interface knows no linear velocity
    monkeypatch.setattr(task, "observation_sources", lambda nominal, lin_vel=False:
                        described(nominal))  # fmt: skip
    policy = load_policy(run_dir)
    with pytest.raises(ValueError, match="from base_lin_vel_x on: this run cannot be exported"):
        export_policy(policy, tmp_path / "policy.pt", "torchscript")
    assert main(["export", str(run_dir), "--format", "torchscript"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "cannot be exported" in err
    assert not (run_dir / "export" / "policy.pt").exists()


def test_the_export_command_and_the_deploy_example_take_the_actors_observation(run, capsys):
    pytest.importorskip("onnxscript")
    pytest.importorskip("onnxruntime")
    import runpy
    from pathlib import Path

    preset, run_dir = run
    size = load_policy(run_dir).actor_obs_dim
    assert main(["export", str(run_dir), "--overwrite"]) == 0
    assert f"inputs observation (1, {size}) and state (1, 0)" in capsys.readouterr().out
    example = Path(__file__).resolve().parents[2] / "examples" / "deploy_onnx.py"
    code = runpy.run_path(str(example))["main"]([str(run_dir), "--steps", "5", "--command", "0.5"])
    assert code == 0, capsys.readouterr().err
    assert "over 5 steps" in capsys.readouterr().out
