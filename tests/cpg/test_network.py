"""CPGNetwork: batching, dtypes, devices, state packing, the hopper preset and JointMap."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from cpg_actor.cpg import CPGNetwork, CPGState, JointMap, Topology
from cpg_actor.robots.hopper.cpg import HOPPER_INITIAL, HOPPER_NOMINAL_POSE, hopper_cpg

from .helpers import measured_amplitude, measured_frequency, simulate, wrap


def _network(dtype=torch.float64) -> CPGNetwork:
    initial = {
        "frequency": (1.0, 1.5, 2.0),
        "frequency_gain": 0.3,
        "amplitude": (0.2, 0.3, 0.4),
        "amplitude_gain": 0.1,
        "convergence": (10.0, 15.0, 20.0),
        "coupling_weight": 2.0,
        "phase_bias": torch.tensor([[0, 0.5, 0], [-0.5, 0, 1.1], [0, -1.1, 0]]),
    }
    frozen = {"frequency_gain": False, "amplitude_gain": False}
    return CPGNetwork(Topology.chain(3), 0.01, initial, frozen=frozen).to(dtype)


def _random_inputs(batch: int, n: int, dtype=torch.float64, seed: int = 0):
    g = torch.Generator().manual_seed(seed)

    def rand(*shape):
        return torch.rand(*shape, generator=g, dtype=torch.float64).to(dtype)

    state = CPGState(
        rand(batch, n) * 6 - 3,
        rand(batch, n) * 10,
        rand(batch, n),
        rand(batch, n) - 0.5,
        rand(batch, n) * 4 - 2,
    )
    drive, xi, kappa = rand(batch, n), rand(batch, n) * 2 - 1, rand(batch, n) * 4 - 2
    return state, drive, xi, kappa


def test_batch_equals_rows_run_one_by_one():
    net = _network()
    batch_state, drive, xi, kappa = _random_inputs(5, 3)
    row_states = [CPGState(*(f[b : b + 1] for f in batch_state)) for b in range(5)]
    with torch.no_grad():
        for _ in range(10):
            batch_out, batch_state = net(batch_state, drive, xi, kappa)
            for b in range(5):
                rows = slice(b, b + 1)
                out, row_states[b] = net(row_states[b], drive[rows], xi[rows], kappa[rows])
                torch.testing.assert_close(out.position, batch_out.position[rows])
                torch.testing.assert_close(out.velocity, batch_out.velocity[rows])
    for b in range(5):
        for row_field, batch_field in zip(row_states[b], batch_state, strict=True):
            torch.testing.assert_close(row_field, batch_field[b : b + 1], rtol=1e-12, atol=1e-12)
    # the rows really differ (a broadcasting mix-up could not pass by accident)
    assert batch_state.phase.std(dim=0).min() > 0.1


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
def test_works_in_float32_and_float64(dtype):
    net = _network(dtype)
    assert net.parametrisation.vector.dtype == dtype
    state = net.initial_state(2, amplitude=0.1)
    assert state.phase.dtype == dtype
    out, state = net(state, drive=0.5, xi=torch.zeros(2, 3, dtype=dtype), kappa=0.1)
    assert out.position.dtype == dtype and all(f.dtype == dtype for f in state)


def test_float32_tracks_float64():
    runs = {}
    for dtype in (torch.float32, torch.float64):
        net = _network(dtype)
        net.check_inputs = False
        runs[dtype] = simulate(net, net.initial_state(1, amplitude=0.1), steps=200, drive=0.5)
    np.testing.assert_allclose(runs[torch.float32]["x"], runs[torch.float64]["x"], atol=1e-4)


def test_state_as_tensor_from_tensor_round_trip():
    state, *_ = _random_inputs(4, 3)
    packed = state.as_tensor()
    assert packed.shape == (4, 5, 3)
    for k, field in enumerate(state):
        assert torch.equal(packed[:, k], field)
    restored = CPGState.from_tensor(packed)
    assert isinstance(restored, CPGState)
    for a, b in zip(restored, state, strict=True):
        assert torch.equal(a, b)
    # rollout storage adds a time dimension: (T, B, 5, N) round-trips too
    stacked = torch.stack([packed, packed + 1])
    assert torch.equal(CPGState.from_tensor(stacked).amplitude[1], state.amplitude + 1)


def test_initial_state_is_at_rest_with_the_preset_phases():
    net = hopper_cpg(0.01)
    state = net.initial_state(3, amplitude=0.2)
    assert torch.equal(state.phase, torch.tensor([[0.0, math.pi]] * 3))
    assert torch.equal(state.amplitude, torch.full((3, 2), 0.2))
    for field in (state.phase_velocity, state.amplitude_velocity, state.amplitude_acceleration):
        assert torch.equal(field, torch.zeros(3, 2))


@pytest.mark.skipif(not torch.cuda.is_available(), reason="CUDA is not available on this machine")
def test_step_on_cuda_matches_cpu():
    net = _network()
    state, drive, xi, kappa = _random_inputs(4, 3)
    expected_out, expected_state = net(state, drive, xi, kappa)
    cuda = torch.device("cuda")
    net_cuda = _network().to(cuda)
    moved = CPGState(*(f.to(cuda) for f in state))
    out, next_state = net_cuda(moved, drive.to(cuda), xi.to(cuda), kappa.to(cuda))
    assert out.position.device.type == "cuda"
    torch.testing.assert_close(out.position.cpu(), expected_out.position)
    for a, b in zip(next_state, expected_state, strict=True):
        torch.testing.assert_close(a.cpu(), b)
    out.position.sum().backward()
    assert net_cuda.parametrisation.vector.grad.device.type == "cuda"


def test_hopper_preset_settles_in_antiphase_around_the_nominal_pose():
    net = hopper_cpg(0.005, check_inputs=False).double()
    assert net.parametrisation.num_parameters == 8
    assert net.topology.names == ("HFE", "KFE")
    values = net.parametrisation.values()
    assert values["phase_bias"][0, 1].item() == pytest.approx(math.pi)
    run = simulate(net, net.initial_state(1), steps=800)
    late = run["t"] > 2.0
    x = run["x"][late, 0]
    for i, joint in enumerate(("HFE", "KFE")):
        assert measured_frequency(run["t"][late], x[:, i]) == pytest.approx(
            HOPPER_INITIAL["frequency"], rel=0.01
        ), joint
        assert measured_amplitude(x[:, i]) == pytest.approx(
            HOPPER_INITIAL["amplitude"][i], rel=0.01
        ), joint
    theta = run["phase"][-1, 0]
    assert abs(wrap(theta[1] - theta[0] - math.pi)) < 0.01
    # antiphase with twice the amplitude: the knee offset is -2x the hip offset
    np.testing.assert_allclose(x[:, 1], -2 * x[:, 0], atol=2e-3)
    positions = JointMap(HOPPER_NOMINAL_POSE)(torch.as_tensor(x))
    np.testing.assert_allclose(positions.mean(0).numpy(), HOPPER_NOMINAL_POSE, atol=5e-3)


def test_joint_map_offsets_fixed_or_learnable():
    fixed = JointMap(HOPPER_NOMINAL_POSE)
    assert list(fixed.parameters()) == []
    x = torch.tensor([[0.1, -0.2]])
    assert torch.allclose(fixed(x), x + torch.tensor(HOPPER_NOMINAL_POSE))
    learnable = JointMap(HOPPER_NOMINAL_POSE, learnable_offset=True)
    assert [p.shape for p in learnable.parameters()] == [torch.Size([2])]
    with pytest.raises(ValueError, match="3 oscillators, the joint map expects 2"):
        fixed(torch.zeros(1, 3))
