"""Order of accuracy of the discrete CPG (eq. 2) against the continuous-time Hopf equations.

The continuous system (Ijspeert et al. 2007, with the paper's feedback terms) is

    theta_dot = 2 pi nu + zeta(theta, r) + xi
    r_ddot    = a (a/4 (rho - r) - r_dot) + kappa

hopf.py derives that eq. 2, which averages the derivatives computed from the states at t-1
and t-2, is a FIRST-order method. Here the global error against a tight ``solve_ivp``
solution is measured over several halvings of dt; the same harness applied to Heun's
method (a genuine second-order trapezoidal scheme) measures 2, so a wrong claim of second
order would be caught.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from scipy.integrate import solve_ivp

from cpg_actor.cpg import CPGNetwork, CPGState, Topology, amplitude_acceleration, phase_velocity

T_END = 1.0
SAMPLE_TIMES = (0.25, 0.5, 0.75, 1.0)
DTS = tuple(0.01 / 2**k for k in range(5))  # 4 halvings: 0.01 ... 0.000625 s
XI = (0.3, -0.2)
KAPPA = (1.0, -2.0)
THETA0 = (0.3, -0.5)
R0 = (0.1, 0.2)
R_DOT0 = (0.0, 0.5)
INITIAL = {
    "frequency": (1.5, 2.0),
    "amplitude": (0.5, 1.0),
    "convergence": (8.0, 12.0),
    "coupling_weight": 3.0,
    "phase_bias": ((0.0, 1.0), (-1.0, 0.0)),
}


def _network(dt: float) -> CPGNetwork:
    return CPGNetwork(Topology.all_to_all(2), dt, INITIAL, check_inputs=False).double()


def _reference() -> np.ndarray:
    """(len(SAMPLE_TIMES), 6): theta, r, r_dot at the sample times, from solve_ivp."""
    net = _network(0.01)
    p = [t.detach().numpy() for t in net.oscillator_parameters(0.0)]
    nu, rho, a, w, phi = p
    lam = net.parametrisation.coupling.numpy()
    xi, kappa = np.array(XI), np.array(KAPPA)

    def rhs(_t, y):
        theta, r, r_dot = y[:2], y[2:4], y[4:]
        zeta = (lam * w * r[None, :] * np.sin(theta[None, :] - theta[:, None] - phi)).sum(1)
        r_ddot = a * (a / 4 * (rho - r) - r_dot) + kappa
        return np.concatenate([2 * math.pi * nu + zeta + xi, r_dot, r_ddot])

    y0 = np.concatenate([THETA0, R0, R_DOT0])
    sol = solve_ivp(
        rhs, (0.0, T_END), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=SAMPLE_TIMES
    )
    assert sol.success
    return sol.y.T


def _initial_state(net: CPGNetwork, start: str) -> CPGState:
    def row(values):
        return torch.tensor(values, dtype=torch.float64).unsqueeze(0)

    state = CPGState(row(THETA0), row((0.0, 0.0)), row(R0), row(R_DOT0), row((0.0, 0.0)))
    if start == "consistent":
        # the stored derivatives equal the ODE's at t = 0, as on a continuous trajectory
        p = net.oscillator_parameters(0.0)
        lam = net.parametrisation.coupling
        state = state._replace(
            phase_velocity=phase_velocity(p, state, lam, row(XI)).detach(),
            amplitude_acceleration=amplitude_acceleration(p, state, row(KAPPA)).detach(),
        )
    return state


def _cpg_trajectory(dt: float, start: str) -> np.ndarray:
    net = _network(dt)
    state = _initial_state(net, start)
    xi, kappa = torch.tensor(XI, dtype=torch.float64), torch.tensor(KAPPA, dtype=torch.float64)
    samples = {round(t / dt): i for i, t in enumerate(SAMPLE_TIMES)}
    out = np.zeros((len(SAMPLE_TIMES), 6))
    with torch.no_grad():
        for n in range(1, round(T_END / dt) + 1):
            _, state = net(state, 0.0, xi, kappa)
            if n in samples:
                fields = (state.phase, state.amplitude, state.amplitude_velocity)
                out[samples[n]] = torch.cat(fields, dim=-1)[0].numpy()
    return out


def _heun_trajectory(dt: float) -> np.ndarray:
    """Heun's method on the same right-hand side (built from the package's eq. 1 terms)."""
    net = _network(dt)
    p = net.oscillator_parameters(0.0)
    lam = net.parametrisation.coupling
    xi, kappa = torch.tensor(XI, dtype=torch.float64), torch.tensor(KAPPA, dtype=torch.float64)

    def rhs(y: torch.Tensor) -> torch.Tensor:
        zero = torch.zeros_like(y[:, :2])
        state = CPGState(y[:, :2], zero, y[:, 2:4], y[:, 4:], zero)
        theta_dot = phase_velocity(p, state, lam, xi)
        return torch.cat([theta_dot, y[:, 4:], amplitude_acceleration(p, state, kappa)], dim=1)

    y = torch.tensor([THETA0 + R0 + R_DOT0], dtype=torch.float64)
    samples = {round(t / dt): i for i, t in enumerate(SAMPLE_TIMES)}
    out = np.zeros((len(SAMPLE_TIMES), 6))
    with torch.no_grad():
        for n in range(1, round(T_END / dt) + 1):
            slope = rhs(y)
            y = y + 0.5 * dt * (slope + rhs(y + dt * slope))
            if n in samples:
                out[samples[n]] = y[0].numpy()
    return out


def _observed_orders(trajectory) -> tuple[list[float], list[float]]:
    reference = _reference()
    errors = [float(np.abs(trajectory(dt) - reference).max()) for dt in DTS]
    orders = [math.log2(errors[k] / errors[k + 1]) for k in range(len(errors) - 1)]
    return errors, orders


@pytest.mark.parametrize("start", ["consistent", "at_rest"])
def test_cpg_scheme_is_first_order_not_second(start):
    errors, orders = _observed_orders(lambda dt: _cpg_trajectory(dt, start))
    assert errors[-1] < 0.01, errors  # it does converge to the continuous solution
    for order in orders:
        assert 0.85 <= order <= 1.15, (errors, orders)
        assert abs(order - 2.0) > 0.5, (errors, orders)  # the scheme is NOT second order


def test_harness_detects_second_order_on_heun():
    errors, orders = _observed_orders(_heun_trajectory)
    for order in orders:
        assert 1.85 <= order <= 2.15, (errors, orders)
