"""One step against a literal, scalar transcription of the paper's eq. 1 and eq. 2."""

from __future__ import annotations

import math

import pytest
import torch

from cpg_actor.cpg import CPGNetwork, CPGState, Topology


def _paper_step(p: dict, s: dict, dt: float, xi: list, kappa: list) -> tuple[dict, list, list]:
    """Eq. 1 and 2 written out oscillator by oscillator with Python floats."""
    n = len(s["theta"])
    theta_dot, r_ddot = [], []
    for i in range(n):
        zeta = sum(
            p["lam"][i][j]
            * s["r"][j]
            * p["w"][i][j]
            * math.sin(s["theta"][j] - s["theta"][i] - p["phi"][i][j])
            for j in range(n)
        )
        theta_dot.append(2 * math.pi * p["nu"][i] + zeta + xi[i])
        a = p["a"][i]
        r_ddot.append(a * (a / 4 * (p["rho"][i] - s["r"][i]) - s["r_dot"][i]) + kappa[i])
    new = {"theta": [], "theta_dot": theta_dot, "r": [], "r_dot": [], "r_ddot": r_ddot}
    for i in range(n):
        new["theta"].append(s["theta"][i] + (s["theta_dot"][i] + theta_dot[i]) * dt / 2)
        new["r_dot"].append(s["r_dot"][i] + (s["r_ddot"][i] + r_ddot[i]) * dt / 2)
        new["r"].append(s["r"][i] + (s["r_dot"][i] + new["r_dot"][i]) * dt / 2)
    x = [new["r"][i] * math.cos(new["theta"][i]) for i in range(n)]
    x_dot = [
        new["r_dot"][i] * math.cos(new["theta"][i])
        - new["r"][i] * math.sin(new["theta"][i]) * theta_dot[i]
        for i in range(n)
    ]
    return new, x, x_dot


def test_step_matches_the_papers_equations_written_out():
    dt = 0.02
    phi = [[0.0, 0.7, 0.0], [-0.7, 0.0, 2.0], [0.0, -2.0, 0.0]]
    w = [[0.0, 3.0, 0.0], [3.0, 0.0, 1.5], [0.0, 1.5, 0.0]]
    initial = {
        "frequency": (1.0, 1.7, 2.3),
        "amplitude": (0.3, 0.5, 0.8),
        "convergence": (5.0, 12.0, 20.0),
        "coupling_weight": torch.tensor(w, dtype=torch.float64),
        "phase_bias": torch.tensor(phi, dtype=torch.float64),
    }
    default = torch.get_default_dtype()
    torch.set_default_dtype(torch.float64)  # initial values exact in float64
    try:
        net = CPGNetwork(Topology.chain(3), dt, initial)
    finally:
        torch.set_default_dtype(default)
    assert net.parametrisation.vector.dtype == torch.float64
    p = {
        "nu": list(initial["frequency"]),
        "rho": list(initial["amplitude"]),
        "a": list(initial["convergence"]),
        "w": w,
        "phi": phi,
        "lam": [[0, 1, 0], [1, 0, 1], [0, 1, 0]],
    }
    s = {
        "theta": [0.1, 2.0, -1.0],
        "theta_dot": [6.0, 11.0, 14.0],
        "r": [0.2, 0.6, 0.1],
        "r_dot": [0.5, -0.3, 1.0],
        "r_ddot": [3.0, -2.0, 8.0],
    }
    xi, kappa = [0.4, -0.8, 1.2], [2.0, 0.0, -3.0]
    state = CPGState(
        *(
            torch.tensor([s[k]], dtype=torch.float64)
            for k in ("theta", "theta_dot", "r", "r_dot", "r_ddot")
        )
    )
    xi_t = torch.tensor(xi, dtype=torch.float64)
    kappa_t = torch.tensor(kappa, dtype=torch.float64)
    for _ in range(5):  # several steps: the stored derivatives are used as eq. 2 says
        s, x, x_dot = _paper_step(p, s, dt, xi, kappa)
        out, state = net(state, 0.0, xi_t, kappa_t)
        assert out.position[0].tolist() == pytest.approx(x, rel=1e-12, abs=1e-12)
        assert out.velocity[0].tolist() == pytest.approx(x_dot, rel=1e-12, abs=1e-12)
        for key, field in zip(("theta", "theta_dot", "r", "r_dot", "r_ddot"), state, strict=True):
            assert field[0].tolist() == pytest.approx(s[key], rel=1e-12, abs=1e-12), key
