"""Differentiability of one CPG step (section III-A): gradcheck and gradient reach."""

from __future__ import annotations

import math

import pytest
import torch
from torch.autograd import gradcheck
from torch.func import functional_call

from cpg_actor.cpg import CPGNetwork, CPGState, Topology
from cpg_actor.robots.hopper.cpg import hopper_cpg

VECTOR = "parametrisation.vector"


def _random_state(batch: int, n: int, seed: int = 0) -> CPGState:
    g = torch.Generator().manual_seed(seed)

    def rand(low, high):
        return low + (high - low) * torch.rand(batch, n, generator=g, dtype=torch.float64)

    return CPGState(
        phase=rand(-math.pi, math.pi),
        phase_velocity=rand(5.0, 15.0),
        amplitude=rand(0.1, 0.5),
        amplitude_velocity=rand(-1.0, 1.0),
        amplitude_acceleration=rand(-5.0, 5.0),
    )


def _chain_with_gains() -> CPGNetwork:
    """Three oscillators, asymmetric coupling (no ties) and trainable drive gains."""
    initial = {
        "frequency": (1.0, 1.5, 2.0),
        "frequency_gain": 0.3,
        "amplitude": (0.2, 0.3, 0.4),
        "amplitude_gain": 0.1,
        "convergence": (10.0, 15.0, 20.0),
        "coupling_weight": torch.tensor([[0, 2.0, 0], [3.0, 0, 1.0], [0, 4.0, 0]]),
        "phase_bias": torch.tensor([[0, 0.5, 0], [-0.7, 0, 1.1], [0, 0.2, 0]]),
    }
    return CPGNetwork(
        Topology.chain(3),
        0.01,
        initial,
        frozen={"frequency_gain": False, "amplitude_gain": False},
        symmetric_coupling=False,
    ).double()


def _step_function(net: CPGNetwork):
    def step(vector, drive, xi, kappa, *state_fields):
        out, next_state = functional_call(
            net, {VECTOR: vector}, (CPGState(*state_fields), drive, xi, kappa)
        )
        return (*out, *next_state)

    return step


@pytest.mark.parametrize("which", ["hopper", "chain_with_gains"])
def test_gradcheck_step_wrt_vector_feedback_drive_and_state(which):
    net = hopper_cpg(0.01).double() if which == "hopper" else _chain_with_gains()
    n, batch = net.num_oscillators, 3
    g = torch.Generator().manual_seed(1)
    vector = net.parametrisation.vector.detach().clone().requires_grad_(True)
    drive = (0.5 + torch.rand(batch, n, generator=g, dtype=torch.float64)).requires_grad_(True)
    xi = torch.randn(batch, n, generator=g, dtype=torch.float64).requires_grad_(True)
    kappa = torch.randn(batch, n, generator=g, dtype=torch.float64).requires_grad_(True)
    state = [f.requires_grad_(True) for f in _random_state(batch, n)]
    inputs = (vector, drive, xi, kappa, *state)
    assert gradcheck(_step_function(net), inputs, eps=1e-6, atol=1e-7, rtol=1e-5)


@pytest.mark.parametrize("which", ["hopper", "chain_with_gains"])
def test_loss_gradient_reaches_every_trainable_entry(which):
    net = hopper_cpg(0.01).double() if which == "hopper" else _chain_with_gains()
    n = net.num_oscillators
    state = _random_state(4, n, seed=2)
    out, _ = net(state, drive=0.7)
    weights = torch.randn(2, 4, n, generator=torch.Generator().manual_seed(3), dtype=torch.float64)
    loss = (weights[0] * out.position).sum() + (weights[1] * out.velocity).sum()
    loss.backward()
    grad = net.parametrisation.vector.grad
    expected = 8 if which == "hopper" else 3 * 5 + 2 * 4  # hopper: 2x(nu, rho, a) + w + phi
    assert grad is not None and grad.shape == (expected,)
    assert torch.isfinite(grad).all()
    assert (grad.abs() > 1e-8).all(), grad


def test_gradient_flows_into_feedback_and_previous_state():
    # PPO replays one step from the stored state: gradients reach xi, kappa (the MLP's outputs)
    net = hopper_cpg(0.01).double()
    state = CPGState(*(f.requires_grad_(True) for f in _random_state(2, 2, seed=4)))
    xi = torch.zeros(2, 2, dtype=torch.float64, requires_grad=True)
    kappa = torch.zeros(2, 2, dtype=torch.float64, requires_grad=True)
    out, _ = net(state, xi=xi, kappa=kappa)
    out.position.sum().backward()
    for tensor in (xi, kappa, *state):
        assert tensor.grad is not None and (tensor.grad.abs() > 0).all()
