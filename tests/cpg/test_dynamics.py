"""Limit-cycle behaviour of eq. 1-2, measured from the output trajectory x = r cos(theta)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from cpg_actor.cpg import CPGNetwork, CPGState, Topology

from .helpers import (
    measured_amplitude,
    measured_frequency,
    simulate,
    single_oscillator,
    upward_zero_crossings,
    wrap,
)

DT = 2e-3


def test_uncoupled_oscillators_converge_to_rho_and_nu():
    frequency, amplitude = (1.5, 3.0), (0.7, 0.2)
    initial = {"frequency": frequency, "amplitude": amplitude, "convergence": 10.0}
    net = CPGNetwork(Topology(2), DT, initial, check_inputs=False).double()  # no edges
    run = simulate(net, net.initial_state(1, amplitude=0.01), steps=2000)
    late = run["t"] > 2.0  # r converges with time constant 2/a = 0.2 s
    for i in range(2):
        x = run["x"][late, 0, i]
        assert measured_frequency(run["t"][late], x) == pytest.approx(frequency[i], rel=0.01)
        assert measured_amplitude(x) == pytest.approx(amplitude[i], rel=0.01)
        # it really started small and grew
        assert measured_amplitude(run["x"][:25, 0, i]) < 0.2 * amplitude[i]


def _coupled_pair(phase_bias: float, dt: float = DT) -> CPGNetwork:
    initial = {
        "frequency": 2.0,
        "amplitude": (1.0, 0.5),
        "convergence": 10.0,
        "coupling_weight": 4.0,
        "phase_bias": ((0.0, phase_bias), (-phase_bias, 0.0)),
    }
    return CPGNetwork(Topology.all_to_all(2), dt, initial, check_inputs=False).double()


def test_coupled_pair_locks_to_commanded_phase_difference():
    phi = 1.2  # not pi: a sign error in the coupling would lock to -1.2 instead
    net = _coupled_pair(phi)
    initial_difference = torch.tensor([0.0, 2.5, -2.0, 3.5, 1.2])  # one batch row each
    phase = torch.stack([torch.full((5,), 0.3), 0.3 + initial_difference], dim=1)
    state = net.initial_state(5, amplitude=0.05, phase=phase)
    assert (np.abs(wrap((initial_difference - phi).numpy())) > 1.0).sum() == 4  # far from phi
    run = simulate(net, state, steps=2000)
    late = run["t"] > 2.5
    t = run["t"][late]
    for row in range(5):
        theta = run["phase"][-1, row]
        assert abs(wrap(theta[1] - theta[0] - phi)) < 0.01
        # measured on the outputs: x_1 leads x_0 by phi / (2 pi nu) seconds
        x = run["x"][late, row]
        frequency = measured_frequency(t, x[:, 0])
        assert frequency == pytest.approx(2.0, rel=0.01)
        lead = upward_zero_crossings(t, x[:, 0])[-1] - upward_zero_crossings(t, x[:, 1])[-1]
        assert abs(wrap(2 * math.pi * frequency * lead - phi)) < 0.01
        # and each oscillator keeps its own rho
        assert measured_amplitude(x[:, 0]) == pytest.approx(1.0, rel=0.01)
        assert measured_amplitude(x[:, 1]) == pytest.approx(0.5, rel=0.01)


def test_constant_xi_shifts_frequency_by_xi_over_two_pi():
    xi = torch.tensor([[0.0], [2.0], [-1.5]], dtype=torch.float64)  # per batch row
    net = single_oscillator(DT, frequency=2.0, amplitude=0.5)
    run = simulate(net, net.initial_state(3, amplitude=0.5), steps=2000, xi=xi)
    late = run["t"] > 1.0
    measured = [measured_frequency(run["t"][late], run["x"][late, row, 0]) for row in range(3)]
    assert measured[0] == pytest.approx(2.0, rel=0.01)
    for row in (1, 2):
        shift = measured[row] - measured[0]
        assert shift == pytest.approx(float(xi[row, 0]) / (2 * math.pi), rel=0.01)


def test_constant_kappa_shifts_amplitude_by_four_kappa_over_a_squared():
    # steady state: r_ddot = 0 and r_dot = 0  =>  a^2/4 (rho - r) + kappa = 0
    #                                         =>  r = rho + 4 kappa / a^2
    rho, convergence = 0.5, torch.tensor([10.0, 20.0, 10.0, 20.0], dtype=torch.float64)
    kappa = torch.tensor([5.0, 20.0, -5.0, 0.0], dtype=torch.float64)
    initial = {"frequency": 2.0, "amplitude": rho, "convergence": convergence}
    net = CPGNetwork(Topology(4), DT, initial, check_inputs=False).double()  # no edges
    run = simulate(net, net.initial_state(1, amplitude=rho), steps=1500, kappa=kappa)
    late = run["t"] > 1.5
    expected = 4 * kappa / convergence**2
    for i in range(4):
        shift = measured_amplitude(run["x"][late, 0, i]) - rho
        assert shift == pytest.approx(float(expected[i]), rel=0.01, abs=1e-3)
    assert expected[:3].abs().min() > 0.1  # the shifts are large enough to be measured


def test_drive_law_sets_measured_frequency_and_amplitude():
    # nu(d) = c_nu1 d + c_nu0, rho(d) = c_R1 d + c_R0
    c_nu0, c_nu1, c_r0, c_r1 = 1.5, 0.75, 0.2, 0.1
    net = CPGNetwork(
        Topology(1),
        DT,
        {
            "frequency": c_nu0,
            "frequency_gain": c_nu1,
            "amplitude": c_r0,
            "amplitude_gain": c_r1,
            "convergence": 20.0,
        },
        frozen={"frequency_gain": False, "amplitude_gain": False},
        check_inputs=False,
    ).double()
    drives = (0.0, 2.0)
    drive = torch.tensor(drives, dtype=torch.float64).unsqueeze(1)  # (B, N): one per row
    run = simulate(net, net.initial_state(2, amplitude=0.1), steps=2000, drive=drive)
    late = run["t"] > 1.5
    for row, drive in enumerate(drives):
        x = run["x"][late, row, 0]
        assert measured_frequency(run["t"][late], x) == pytest.approx(
            c_nu1 * drive + c_nu0, rel=0.01
        )
        assert measured_amplitude(x) == pytest.approx(c_r1 * drive + c_r0, rel=0.01)


def test_x_dot_is_the_time_derivative_of_x():
    net = _coupled_pair(1.0, dt=1e-3)
    run = simulate(net, net.initial_state(1, amplitude=0.2), steps=1000)
    x, x_dot = run["x"][:, 0], run["x_dot"][:, 0]
    central = (x[2:] - x[:-2]) / (2 * net.dt)
    scale = np.abs(x_dot).max()
    assert np.abs(central - x_dot[1:-1]).max() < 0.02 * scale


def test_step_is_pure_and_stateless():
    net = _coupled_pair(0.5)
    state = net.initial_state(3, amplitude=0.3)
    state = CPGState(*(f + 0.1 * torch.randn_like(f) for f in state))
    copies = [f.clone() for f in state]
    first = net(state, 0.0, 0.2, -0.1)
    second = net(state, 0.0, 0.2, -0.1)
    for a, b in zip(first[0] + first[1], second[0] + second[1], strict=True):
        assert torch.equal(a, b)
    for before, after in zip(copies, state, strict=True):
        assert torch.equal(before, after)
    assert not any(name != "initial_phase" for name, _ in net.named_buffers(recurse=False))


def test_amplitude_dynamics_stability_limit():
    # The linear r-subsystem of eq. 1-2 (state r, r_dot, previous r_ddot) has spectral radius
    # < 1 exactly for a dt < 6 - 2 sqrt(5) ~ 1.528 (docs/cpg.md): converge below, diverge above.
    # The network caps a at 1 / dt (MAX_CONVERGENCE_STEP), so through it all three settle.
    from cpg_actor.cpg import hopf_step
    from cpg_actor.cpg.network import MAX_CONVERGENCE_STEP

    limit = 6 - 2 * math.sqrt(5)
    dt = 0.01
    convergence = torch.tensor([0.6 * limit / dt, 0.97 * limit / dt, 1.05 * limit / dt])
    initial = {"frequency": 1.0, "amplitude": 0.5, "convergence": convergence.double()}
    net = CPGNetwork(Topology(3), dt, initial, check_inputs=False).double()
    params = net.parametrisation.oscillator_parameters()  # uncapped: the scheme itself
    state = net.initial_state(1, amplitude=0.1)
    with torch.no_grad():
        for _ in range(1500):
            _, state = hopf_step(params, state, net.parametrisation.coupling, dt)
    r = state.amplitude[0].numpy()
    assert np.abs(r[:2] - 0.5).max() < 1e-6  # stable: settled on rho
    assert np.abs(r[2] - 0.5) > 10.0 or not np.isfinite(r[2])  # unstable: blew up

    capped = net.oscillator_parameters().convergence
    assert torch.equal(capped[0], params.convergence[0])  # below the cap (a dt = 0.92): unchanged
    assert capped[1:].tolist() == pytest.approx([MAX_CONVERGENCE_STEP / dt] * 2)
    run = simulate(net, net.initial_state(1, amplitude=0.1), steps=1500)
    assert np.abs(run["amplitude"][-100:, 0] - 0.5).max() < 1e-6  # through the network: all
