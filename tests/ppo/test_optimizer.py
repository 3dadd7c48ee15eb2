"""The lean gradient clip and Adam step compute what torch's own compute, bit for bit."""

import copy

import pytest
import torch

import cpg_actor.ppo.algorithm as algorithm
from cpg_actor.ppo.optimizer import adam_step, clip_grad_norm_

from .fake_env import fake_runner


def network(seed: int = 0) -> torch.nn.Module:
    torch.manual_seed(seed)
    net = torch.nn.Sequential(torch.nn.Linear(5, 16), torch.nn.Tanh(), torch.nn.Linear(16, 3))
    net.register_parameter("gain", torch.nn.Parameter(torch.ones(3)))
    return net


def loss_of(net: torch.nn.Module, step: int) -> torch.Tensor:
    x = torch.randn(32, 5, generator=torch.Generator().manual_seed(step))
    scale = 1e3 if step % 2 else 1e-2  # gradients above and below the clip
    return scale * (net(x) * net.gain).square().mean()


def adam(net: torch.nn.Module, **options) -> torch.optim.Adam:
    params = list(net.parameters())
    groups = [{"params": params[:2]}, {"params": params[2:], "lr": 1e-2}]  # two groups
    return torch.optim.Adam(groups, lr=3e-3, eps=1e-5, **options)


@pytest.mark.parametrize(
    "options", [{"fused": True}, {"foreach": True}, {"fused": True, "weight_decay": 0.1}]
)
def test_clip_and_adam_step_equal_torchs_bit_for_bit(options):
    ours, theirs = network(), network()
    opt_ours, opt_theirs = adam(ours, **options), adam(theirs, **options)
    for step in range(8):
        if step == 5:  # the adaptive schedule changes a group's rate between steps
            for opt in (opt_ours, opt_theirs):
                opt.param_groups[0]["lr"] = 7e-4
        for net in (ours, theirs):
            for p in net.parameters():
                p.grad = None
        loss_of(ours, step).backward()
        loss_of(theirs, step).backward()
        if step == 3:  # a parameter without a gradient is left out, as torch leaves it
            ours.gain.grad = theirs.gain.grad = None
        norm_ours = clip_grad_norm_(list(ours.parameters()), 0.5)
        norm_theirs = torch.nn.utils.clip_grad_norm_(theirs.parameters(), 0.5, foreach=True)
        assert torch.equal(norm_ours, norm_theirs)
        adam_step(opt_ours)
        opt_theirs.step()
        for a, b in zip(ours.parameters(), theirs.parameters(), strict=True):
            assert torch.equal(a, b)
    state_ours, state_theirs = opt_ours.state_dict(), opt_theirs.state_dict()
    assert state_ours["param_groups"] == state_theirs["param_groups"]
    for index, state in state_theirs["state"].items():
        for key, value in state.items():
            assert torch.equal(state_ours["state"][index][key], value), (index, key)


def test_the_clip_scales_to_the_norm_and_falls_back_for_mixed_dtypes():
    a = torch.nn.Parameter(torch.zeros(3))
    b = torch.nn.Parameter(torch.zeros(4))
    a.grad, b.grad = torch.full((3,), 3.0), torch.full((4,), 4.0)
    norm = clip_grad_norm_([a, b], 1.0)
    assert norm.item() == pytest.approx((27 + 64) ** 0.5)
    joint = torch.cat([a.grad, b.grad]).norm().item()
    assert joint == pytest.approx(1.0, rel=1e-5)
    c = torch.nn.Parameter(torch.zeros(2, dtype=torch.float64))
    c.grad = torch.full((2,), 10.0, dtype=torch.float64)
    a.grad = torch.full((3,), 3.0)
    norm = clip_grad_norm_([a, c], 1.0)  # torch's own: two groups
    assert norm.item() == pytest.approx((27 + 200) ** 0.5)


def test_a_ppo_update_equals_one_with_torchs_clip_and_adam(monkeypatch):
    """The CPG-Actor with its CPG in an Adam group of its own (two groups)."""

    def runner():
        return fake_runner(
            "cpg-actor", num_minibatches=4, lr_schedule="adaptive", cpg_learning_rate=1e-4
        )

    ours = runner()  # one after the other: a runner seeds torch's global generator
    for _ in range(2):
        ours.collect()
        ours.ppo.update(ours.storage)
    theirs = runner()
    with monkeypatch.context() as patch:
        patch.setattr(algorithm, "adam_step", lambda optimizer: optimizer.step())
        patch.setattr(
            algorithm,
            "clip_grad_norm_",
            lambda params, norm: torch.nn.utils.clip_grad_norm_(params, norm, foreach=True),
        )
        for _ in range(2):
            theirs.collect()
            theirs.ppo.update(theirs.storage)
    theirs_state = theirs.agent.state_dict()
    for name, value in ours.agent.state_dict().items():
        assert torch.equal(value, theirs_state[name]), name
    assert ours.ppo.learning_rate == theirs.ppo.learning_rate
    copy.deepcopy(ours.ppo.optimizer.state_dict())  # a checkpointable state
