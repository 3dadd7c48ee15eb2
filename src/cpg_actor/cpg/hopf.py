"""The Hopf-oscillator CPG step of the paper, as pure functions (eq. 1, 2 and 3).

One step maps (oscillator parameters, previous state, feedback) to (output, next state):

    eq. 1   theta_dot_i^t = 2 pi nu_i(d^t) + zeta_i^t + xi_i^t
            zeta_i^t      = sum_j Lambda_ij r_j^{t-1} w_ij sin(theta_j^{t-1} - theta_i^{t-1}
                                                                - phi_ij)
            r_ddot_i^t    = a_i (a_i / 4 (rho_i(d^t) - r_i^{t-1}) - r_dot_i^{t-1}) + kappa_i^t
            x_i^t         = r_i^t cos(theta_i^t)

    eq. 2   theta^t = theta^{t-1} + (theta_dot^{t-1} + theta_dot^t) dt / 2
            r_dot^t = r_dot^{t-1} + (r_ddot^{t-1} + r_ddot^t) dt / 2
            r^t     = r^{t-1}     + (r_dot^{t-1} + r_dot^t) dt / 2

The desired velocity sent with x is its exact time derivative given the new state,
``x_dot = r_dot cos(theta) - r sin(theta) theta_dot``.

Order of accuracy. In eq. 1 the derivatives labelled ``t`` are computed from the state at
``t-1``, so the update of eq. 2 for the phase and for ``r_dot`` is
``y_n+1 = y_n + dt/2 (f(y_n-1) + f(y_n))``: the mean of the slopes at the two previous
states, centred at ``t_n-1/2`` instead of the ``t_n+1/2`` of the step, one step too early.
Taylor expansion gives the local error ``y(t+dt) - y(t) - dt/2 (y'(t) + y'(t-dt))
= dt^2 y'' + O(dt^3)``; the method is consistent and zero-stable (characteristic
polynomial ``z^2 - z``, roots 1 and 0), so the global error is first order, O(dt), not the
second order of the classic trapezoidal rule (tests/cpg/test_convergence.py measures it).
The update of ``r`` from ``r_dot`` is trapezoidal, but it inherits the O(dt) error of
``r_dot``. A state built by :meth:`CPGState.initial` is "at rest" (theta_dot = r_ddot = 0),
which adds a one-off O(dt) error in the first step: also first order.

Shapes: batch first. State fields are ``(B, N)``; ``nu``/``rho`` are ``(B, N)`` or ``(N,)``;
``a`` is ``(N,)`` or ``(B, N)``; ``w``, ``phi`` and ``coupling`` (Lambda) are ``(N, N)``, with
entry ``[i, j]`` describing the influence of oscillator ``j`` on oscillator ``i``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import torch
from torch import Tensor

STATE_FIELDS = (
    "phase",
    "phase_velocity",
    "amplitude",
    "amplitude_velocity",
    "amplitude_acceleration",
)


class CPGState(NamedTuple):
    """Everything eq. 2 needs from the previous step, each ``(B, N)``.

    ``phase`` is theta, ``phase_velocity`` theta_dot, ``amplitude`` r, ``amplitude_velocity``
    r_dot and ``amplitude_acceleration`` r_ddot.
    """

    phase: Tensor
    phase_velocity: Tensor
    amplitude: Tensor
    amplitude_velocity: Tensor
    amplitude_acceleration: Tensor

    def as_tensor(self) -> Tensor:
        """Pack into one ``(B, 5, N)`` tensor (e.g. for rollout storage)."""
        return torch.stack(tuple(self), dim=-2)

    @classmethod
    def from_tensor(cls, packed: Tensor) -> CPGState:
        """Inverse of :meth:`as_tensor`."""
        if packed.dim() < 2 or packed.shape[-2] != len(STATE_FIELDS):
            raise ValueError(
                f"a packed CPG state must have shape (..., {len(STATE_FIELDS)}, N), "
                f"got {tuple(packed.shape)}"
            )
        return cls(*packed.unbind(dim=-2))

    @classmethod
    def initial(
        cls,
        batch_size: int,
        num_oscillators: int,
        amplitude: float | Tensor = 0.0,
        phase: float | Tensor = 0.0,
        dtype: torch.dtype = torch.float32,
        device: torch.device | str | None = None,
    ) -> CPGState:
        """A state at rest: the given phase and amplitude, all derivatives zero."""
        shape = (batch_size, num_oscillators)
        zeros = torch.zeros(shape, dtype=dtype, device=device)
        return cls(
            phase=zeros + torch.as_tensor(phase, dtype=dtype, device=device),
            phase_velocity=zeros.clone(),
            amplitude=zeros + torch.as_tensor(amplitude, dtype=dtype, device=device),
            amplitude_velocity=zeros.clone(),
            amplitude_acceleration=zeros.clone(),
        )


class OscillatorParameters(NamedTuple):
    """The physical parameters of eq. 1 for the current drive: nu (Hz), rho, a, w, phi."""

    frequency: Tensor  # nu_i(d), Hz, > 0
    amplitude: Tensor  # rho_i(d), > 0
    convergence: Tensor  # a_i, 1/s, > 0
    coupling_weight: Tensor  # w_ij
    phase_bias: Tensor  # phi_ij, rad


class CPGOutput(NamedTuple):
    """Output of one step: x (eq. 1) and its time derivative, each ``(B, N)``."""

    position: Tensor
    velocity: Tensor


def coupling_term(state: CPGState, weight: Tensor, phase_bias: Tensor, coupling: Tensor) -> Tensor:
    """zeta_i = sum_j Lambda_ij r_j w_ij sin(theta_j - theta_i - phi_ij) (eq. 1; Z 1 of eq. 3)."""
    theta = state.phase
    phase_difference = theta.unsqueeze(-2) - theta.unsqueeze(-1)  # [..., i, j] = theta_j - theta_i
    terms = (
        coupling * weight * state.amplitude.unsqueeze(-2) * torch.sin(phase_difference - phase_bias)
    )
    return terms.sum(dim=-1)


def phase_velocity(
    params: OscillatorParameters, state: CPGState, coupling: Tensor, xi: Tensor | float = 0.0
) -> Tensor:
    """theta_dot^t = 2 pi nu + zeta + xi, from the state at t-1 (eq. 1)."""
    zeta = coupling_term(state, params.coupling_weight, params.phase_bias, coupling)
    return 2.0 * math.pi * params.frequency + zeta + xi


def amplitude_acceleration(
    params: OscillatorParameters, state: CPGState, kappa: Tensor | float = 0.0
) -> Tensor:
    """r_ddot^t = a (a/4 (rho - r^{t-1}) - r_dot^{t-1}) + kappa (eq. 1)."""
    a = params.convergence
    return a * (a / 4.0 * (params.amplitude - state.amplitude) - state.amplitude_velocity) + kappa


def hopf_step(
    params: OscillatorParameters,
    state: CPGState,
    coupling: Tensor,
    dt: float,
    xi: Tensor | float = 0.0,
    kappa: Tensor | float = 0.0,
) -> tuple[CPGOutput, CPGState]:
    """One step of the CPG network: eq. 1 for the derivatives, eq. 2 to integrate them.

    Pure: nothing is stored, the inputs are not modified. Differentiable in ``params``,
    ``state``, ``xi`` and ``kappa``. Returns ``(CPGOutput(x, x_dot), next_state)``.
    """
    theta_dot = phase_velocity(params, state, coupling, xi)
    r_ddot = amplitude_acceleration(params, state, kappa)
    half_dt = 0.5 * dt
    theta = state.phase + (state.phase_velocity + theta_dot) * half_dt
    r_dot = state.amplitude_velocity + (state.amplitude_acceleration + r_ddot) * half_dt
    r = state.amplitude + (state.amplitude_velocity + r_dot) * half_dt
    cos_theta = torch.cos(theta)
    x = r * cos_theta
    x_dot = r_dot * cos_theta - r * torch.sin(theta) * theta_dot
    next_state = CPGState(theta, theta_dot, r, r_dot, r_ddot)
    return CPGOutput(x, x_dot), next_state
