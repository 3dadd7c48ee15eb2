"""Shared helpers for the CPG tests: run a network, measure frequency and amplitude of x."""

from __future__ import annotations

import math

import numpy as np
import torch

from cpg_actor.cpg import CPGNetwork, CPGState, Topology


def single_oscillator(
    dt: float = 1e-3,
    frequency: float = 1.5,
    amplitude: float = 0.7,
    convergence: float = 10.0,
    dtype: torch.dtype = torch.float64,
) -> CPGNetwork:
    """One uncoupled oscillator (no edges: zeta = 0)."""
    net = CPGNetwork(
        Topology(1),
        dt,
        {"frequency": frequency, "amplitude": amplitude, "convergence": convergence},
        check_inputs=False,
    )
    return net.to(dtype)


def simulate(
    net: CPGNetwork,
    state: CPGState,
    steps: int,
    drive=0.0,
    xi=0.0,
    kappa=0.0,
) -> dict[str, np.ndarray]:
    """Run ``steps`` steps; returns time ``t`` (after each step) and ``(steps, B, N)`` traces."""
    keys = ("x", "x_dot", "phase", "phase_velocity", "amplitude", "amplitude_acceleration")
    traces: dict[str, list] = {k: [] for k in keys}
    with torch.no_grad():
        for _ in range(steps):
            out, state = net(state, drive, xi, kappa)
            traces["x"].append(out.position)
            traces["x_dot"].append(out.velocity)
            for k in keys[2:]:
                traces[k].append(getattr(state, k))
    result = {k: torch.stack(v).cpu().double().numpy() for k, v in traces.items()}
    result["t"] = net.dt * np.arange(1, steps + 1)
    result["state"] = state
    return result


def upward_zero_crossings(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Times where ``x`` crosses 0 going up, linearly interpolated between samples."""
    idx = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    return t[idx] - x[idx] * (t[idx + 1] - t[idx]) / (x[idx + 1] - x[idx])


def measured_frequency(t: np.ndarray, x: np.ndarray) -> float:
    """Mean frequency (Hz) of ``x`` from its upward zero crossings."""
    crossings = upward_zero_crossings(t, x)
    if len(crossings) < 3:
        raise AssertionError(f"only {len(crossings)} zero crossings: no oscillation to measure")
    return (len(crossings) - 1) / (crossings[-1] - crossings[0])


def measured_amplitude(x: np.ndarray) -> float:
    """Peak amplitude of ``x`` (mean of max and -min)."""
    return 0.5 * (float(np.max(x)) - float(np.min(x)))


def wrap(angle: float | np.ndarray) -> float | np.ndarray:
    """Wrap an angle to (-pi, pi]."""
    return -((-np.asarray(angle) + math.pi) % (2 * math.pi) - math.pi)
