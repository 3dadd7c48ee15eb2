"""`--device`: networks, storage, normalisers and PPO on a chosen device; the CPU default.
The CUDA tests run where torch sees a GPU and are skipped elsewhere."""

import pytest
import torch

from cpg_actor.cli import main
from cpg_actor.config import TrainConfig
from cpg_actor.deploy import load_policy
from cpg_actor.device import check_device_name, resolve_device
from cpg_actor.ppo import PPOConfig
from cpg_actor.training.runner import Runner

CUDA = torch.cuda.is_available()


def test_device_names_are_checked_and_auto_picks_what_exists():
    for name in ("cpu", "cuda", "cuda:1", "auto"):
        check_device_name(name)
    for name in ("gpu", "CUDA", "cuda:x", ""):
        with pytest.raises(ValueError, match="device must be cpu, cuda, cuda:N or auto"):
            check_device_name(name)
    assert resolve_device("auto").type == ("cuda" if CUDA else "cpu")
    assert resolve_device("cpu") == torch.device("cpu")
    with pytest.raises(ValueError, match="device must be"):
        TrainConfig(device="gpu").validate()


@pytest.mark.skipif(CUDA, reason="checks the message on a machine without CUDA")
def test_asking_for_cuda_without_a_gpu_says_so(tmp_path, capsys):
    with pytest.raises(ValueError, match="torch sees no CUDA device here.*--device cpu or auto"):
        resolve_device("cuda")
    code = main(["train", "--device", "cuda", "--run-dir", str(tmp_path / "run")])
    assert code == 2 and "no CUDA device" in capsys.readouterr().err
    assert not (tmp_path / "run" / "checkpoints").exists()


def config(agent: str, device: str, iterations: int = 4) -> TrainConfig:
    return TrainConfig(
        agent=agent,
        device=device,
        num_envs=4,
        total_steps=iterations * 4 * 16,
        ppo=PPOConfig(num_steps=16, num_epochs=2, num_minibatches=4, compile=False),
        eval_interval=2,
        eval_episodes=2,
        checkpoint_interval=2,
    )


@pytest.mark.skipif(not CUDA, reason="needs a CUDA device")
@pytest.mark.parametrize("agent", ["cpg-actor", "mlp", "cho2019-warm"])
def test_training_on_cuda_runs_and_resumes(tmp_path, agent):
    """CUDA draws its action noise from its own generator: a CUDA run is not the CPU run with
    the same seed, but it is reproducible and resumes."""
    straight = Runner(config(agent, "cuda"), run_dir=tmp_path / "cuda", tensorboard=False)
    straight.learn()
    assert straight.storage.observations.device.type == "cuda"
    assert all(p.device.type == "cuda" for p in straight.agent.parameters())
    resumed = Runner(config(agent, "cuda"), run_dir=tmp_path / "copy", tensorboard=False)
    resumed.load_checkpoint(tmp_path / "cuda" / "checkpoints" / "iter_000002.pt")
    resumed.learn()
    try:
        # the same run (CUDA's atomic adds may reorder float sums: equal up to rounding)
        for key, value in straight.agent.state_dict().items():
            torch.testing.assert_close(value, resumed.agent.state_dict()[key], rtol=1e-5, atol=1e-6)
        assert straight.last_evaluation["eval/return"] == pytest.approx(
            resumed.last_evaluation["eval/return"], rel=1e-4
        )
    finally:
        for runner in (straight, resumed):
            runner.close()
    policy = load_policy(tmp_path / "cuda", device="cuda")
    policy.reset(2)
    obs_dim = policy.normalizer.mean.shape[0]
    assert policy.act(torch.zeros(2, obs_dim)).action.shape[0] == 2
