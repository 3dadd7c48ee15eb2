"""Training on the MJX hopper (JAX's CPU backend here; the same code runs on a GPU): every
kind of agent trains, the env's tensors reach PPO without numpy, a control step of the rollout
never reads a value on the host, the evaluation runs on MJX envs on the device with the
numbers of the numpy loop and changes nothing that is trained (resume on MJX:
tests/training/test_checkpoint_episodes.py)."""

import numpy as np
import pytest
import torch

from cpg_actor.robots.common import mjx_runtime as runtime  # noqa: E402

if not runtime.available():
    pytest.skip('the MJX backend needs pip install -e ".[mjx]"', allow_module_level=True)

import jax  # noqa: E402

from cpg_actor.host_reads import host_reads  # noqa: E402
from cpg_actor.robots.hopper.mjx.vector import MjxHopperVectorEnv  # noqa: E402
from cpg_actor.robots.hopper.vector import make_vector_env  # noqa: E402
from cpg_actor.training.evaluation import CHECK_EVERY, evaluate  # noqa: E402
from cpg_actor.training.policy import Policy  # noqa: E402
from cpg_actor.training.runner import Runner  # noqa: E402
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


def test_host_reads_sees_every_kind_of_read():
    """The guard of the tests below: it records what would wait for a GPU (and JAX's
    transfer_guard does not flag device-to-host reads on its CPU backend)."""
    array, tensor = jax.numpy.arange(3.0), torch.arange(3.0)
    with host_reads() as reads:
        assert bool(array[1] > 0.5) and np.asarray(array).shape == (3,)
        assert float(tensor[2]) == 2.0 and tensor.sum().item() == 3.0 and bool(tensor.any())
        assert tensor.cpu().numpy().shape == (3,)
    assert reads == ["ArrayImpl.__bool__", "numpy.asarray(ArrayImpl)", "Tensor.__float__",
                     "Tensor.item", "Tensor.__bool__", "Tensor.cpu", "Tensor.numpy"]  # fmt: skip
    with host_reads() as reads:
        _ = array + 1.0, tensor * 2.0, torch.from_dlpack(array)  # on the device: no read
    assert reads == [] and "__bool__" not in vars(torch.Tensor)  # the classes restored
    assert bool(tensor.any())


@pytest.mark.parametrize("agent", ["cpg-actor", "mlp", "cho2019"])
def test_a_rollout_step_never_waits_for_the_device(agent):
    """Seven control steps of the rollout, across episode ends (3-step episodes): no value is
    read on the host and nothing is copied there from the host; the episodes that ended
    reach the log at the rollout's one flush, with the numbers of the per-step path."""
    config = mjx_config(agent)
    config.env.episode_steps = 3
    runner = Runner(config, tensorboard=False)
    try:
        assert runner.rollout.sync_free and runner.rollout.episodes.deferred
        runner.start_episodes()
        runner.collect()  # compiles, and makes what the first step makes once
        runner.storage.clear()
        logged = len(runner.rollout.episodes.recent["length"])
        with host_reads() as reads, jax.transfer_guard("disallow"):
            for _ in range(7):
                runner.rollout.step()
        assert reads == []
        assert len(runner.rollout.episodes.recent["length"]) == logged  # waiting on the device
        episodes = runner.rollout.episodes
        episodes.flush()
        lengths = list(episodes.recent["length"])
        assert lengths[logged:] == [3.0] * 6 and np.isfinite(episodes.recent["return"]).all()
    finally:
        runner.close()


def test_nan_actions_on_mjx_stop_the_run_at_the_end_of_the_rollout():
    from cpg_actor.training.runner import TrainingDiverged

    runner = Runner(mjx_config("mlp"), tensorboard=False)
    try:
        runner.start_episodes()
        with torch.no_grad():  # NaN actions (a NaN std: torch.normal refuses it on the CPU)
            for name, value in runner.agent.named_parameters():
                if name != "log_std":
                    value.fill_(float("nan"))
        with pytest.raises(TrainingDiverged, match="actions became NaN or inf"):
            runner.collect()
    finally:
        runner.close()


def test_evaluation_on_the_device_equals_the_numpy_loop():
    """evaluate() without traces on an MJX env runs on the device: the numbers of the numpy
    loop exactly, and a fixed number of host reads, whatever the episode's length."""
    runner = Runner(mjx_config("cpg-actor"), tensorboard=False)
    bounds = runner.policy.action_low, runner.policy.action_high
    policy = Policy(runner.agent, runner.normalizer, *bounds)
    reads = {}
    try:
        for steps in (12, 24):  # one compilation: the episode length is a value
            env = make_vector_env(2, sim="mjx", episode_steps=steps)
            with host_reads() as reads[steps]:
                device = evaluate(policy, env, seed=4, control_dt=0.01, max_steps=steps,
                                  traces=False)  # fmt: skip
            host = evaluate(policy, env, seed=4, control_dt=0.01, max_steps=steps,
                            traces=False, on_device=False)  # fmt: skip
            assert set(device) == set(host)
            for key in ("length", "episode_return", "hop_height", "standing_hip_height"):
                np.testing.assert_array_equal(device[key], host[key], err_msg=key)
            assert (device["length"] == steps).all() and (device["hop_height"] >= 0).all()
            env.close()
        assert len(reads[12]) == len(reads[24]) < 12  # none per step (12 and 24 < CHECK_EVERY)
        assert CHECK_EVERY > 24
        with pytest.raises(ValueError, match="traces are recorded on the host"):
            evaluate(policy, env, seed=4, control_dt=0.01, max_steps=2, on_device=True)
    finally:
        runner.close()


def test_evaluation_during_training_on_mjx_changes_nothing_that_is_trained():
    runs = {}
    for interval in (1, 0):
        runner = Runner(mjx_config("cpg-actor", eval_interval=interval, eval_episodes=2),
                        tensorboard=False)  # fmt: skip
        try:
            runner.learn()
            runs[interval] = (params(runner), list(runner.rollout.episodes.recent["return"]))
        finally:
            runner.close()
    for key, value in runs[1][0].items():
        assert torch.equal(value, runs[0][0][key]), key
    assert runs[1][1] == runs[0][1]


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
        assert runner.rollout.obs.is_cuda and runner.policy.state.is_cuda
        assert all(p.is_cuda and torch.isfinite(p).all() for p in runner.agent.parameters())
        hold = torch.tensor([[0.4, -0.8]] * 2, device="cuda")
        out = runner.env.step(hold)  # DLPack both ways: every tensor stays on the GPU
        assert out.obs.is_cuda and out.reward.is_cuda and out.terminated.is_cuda
    finally:
        runner.close()
