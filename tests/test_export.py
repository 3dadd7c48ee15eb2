"""`cpg-actor export`: the exported control step (TorchScript, ONNX via onnxruntime) acts as
the PyTorch policy over a whole evaluation episode, carrying its CPG state."""

import numpy as np
import pytest
import torch

from cpg_actor.cli import main
from cpg_actor.envs import HopperVectorEnv
from cpg_actor.export import export_policy
from cpg_actor.policy import load_policy
from cpg_actor.runner import Runner
from tiny import tiny_config  # tests/tiny.py (pytest puts tests/ on sys.path)


def trained_run(path, agent):
    runner = Runner(tiny_config(agent), run_dir=path, tensorboard=False)
    runner.learn()
    runner.close()
    return path


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


def test_export_command_writes_the_file_and_says_what_it_takes(tmp_path, capsys):
    run_dir = trained_run(tmp_path / "run", "cpg-actor")
    assert main(["export", str(run_dir), "--format", "torchscript"]) == 0
    out = capsys.readouterr().out
    assert "observation (1, 8) and state (1, 5, 2)" in out
    assert (run_dir / "export" / "policy.pt").is_file()
    assert (run_dir / "export" / "policy.pt.initial_state.npy").is_file()
    assert main(["export", str(run_dir), "--format", "torchscript"]) == 2
    assert "exists; pass --overwrite" in capsys.readouterr().err
    assert main(["export", str(tmp_path / "missing")]) == 2


def test_exported_quadruped_policy_reads_its_drive_from_the_raw_command(tmp_path):
    """On the quadruped the exported step sets the CPG's drive from the raw observation (the
    forward-speed command) as the policy does: same actions and states, drive row included."""
    from cpg_actor.config import apply_dict
    from cpg_actor.envs.quadruped.vector import AnymalVectorEnv

    config = tiny_config("cpg-actor")
    apply_dict(config, {"robot": "anymal", "env": {"episode_seconds": 0.2}}, "")
    runner = Runner(config, run_dir=tmp_path / "run", tensorboard=False)
    runner.learn()
    runner.close()
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
