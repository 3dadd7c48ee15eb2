"""Training on the MJX hopper (JAX's CPU backend here; the same code runs on a GPU): every
kind of agent trains, the env's tensors reach PPO without numpy, the evaluation runs on MJX
envs (resume on MJX: tests/ppo/test_checkpoint_episodes.py)."""

import numpy as np
import pytest
import torch

from cpg_actor.envs.mjx import runtime  # noqa: E402

if not runtime.available():
    pytest.skip('the MJX backend needs pip install -e ".[mjx]"', allow_module_level=True)

from cpg_actor.envs.mjx.vector import MjxHopperVectorEnv  # noqa: E402
from cpg_actor.runner import Runner  # noqa: E402
from tiny import tiny_config  # noqa: E402  (tests/tiny.py)


def mjx_config(agent: str, eval_interval: int = 0, **fields):
    config = tiny_config(agent, **fields)
    config.eval_interval = eval_interval
    config.env.sim = "mjx"
    config.env.episode_steps = 12
    return config


def params(runner: Runner) -> dict[str, torch.Tensor]:
    return {k: v.clone() for k, v in runner.agent.state_dict().items()}


@pytest.mark.parametrize("agent", ["cpg-actor", "mlp", "cho2019"])
def test_every_kind_of_agent_trains_on_mjx(agent):
    runner = Runner(mjx_config(agent, eval_interval=2, eval_episodes=2), tensorboard=False)
    try:
        assert isinstance(runner.env.unwrapped.env if agent == "cho2019" else
                          runner.env.unwrapped, MjxHopperVectorEnv)  # fmt: skip
        before = params(runner)
        runner.learn()
        after = params(runner)
        assert all(torch.isfinite(v).all() for v in after.values())
        assert any(not torch.equal(before[k], after[k]) for k in before)
        assert runner.global_step == 32
        evaluation = runner.run_evaluation()
        assert np.isfinite(evaluation["eval/return"])
        assert evaluation["eval/hop_height"] >= 0
    finally:
        runner.close()


def jax_has_gpu() -> bool:
    import jax

    return any(device.platform in ("gpu", "cuda") for device in jax.devices())


@pytest.mark.skipif(
    not (torch.cuda.is_available() and jax_has_gpu()),
    reason="needs CUDA in both torch and JAX (docs/gpu.md)",
)
def test_training_on_the_gpu_keeps_every_tensor_there():
    config = mjx_config("cpg-actor")
    config.device = "cuda"
    runner = Runner(config, tensorboard=False)
    try:
        assert runner.env.unwrapped.device.type == "cuda"
        runner.learn()
        assert runner.obs.is_cuda and runner.agent_state.is_cuda
        assert all(p.is_cuda and torch.isfinite(p).all() for p in runner.agent.parameters())
        hold = torch.tensor([[0.4, -0.8]] * 2, device="cuda")
        out = runner.env.step(hold)  # DLPack both ways: every tensor stays on the GPU
        assert out.obs.is_cuda and out.reward.is_cuda and out.terminated.is_cuda
    finally:
        runner.close()
