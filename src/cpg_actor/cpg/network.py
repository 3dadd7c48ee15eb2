"""`CPGNetwork`: the trainable Hopf CPG of eq. 3 as a PyTorch module with no hidden state."""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Mapping, Sequence

import torch
from torch import Tensor, nn

from cpg_actor.cpg.hopf import CPGOutput, CPGState, OscillatorParameters, hopf_step
from cpg_actor.cpg.parametrisation import Entry, Parametrisation, symmetric_coupling_ties
from cpg_actor.cpg.topology import Topology


def _check_finite(name: str, value: Tensor | float) -> None:
    if isinstance(value, Tensor):
        if not torch.isfinite(value).all():
            raise ValueError(f"{name} contains NaN or inf")
    elif isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(
            f"{name} must be a real number or a torch.Tensor, got {type(value).__name__}"
        )
    elif not math.isfinite(value):
        raise ValueError(f"{name} is {value}; a finite number is required")


def _check_like(name: str, value: Tensor, reference: Tensor) -> None:
    """Same dtype and device as the network (mixing would silently promote or fail later)."""
    if value.device != reference.device:
        raise ValueError(
            f"{name} is on {value.device} but the CPG network is on {reference.device}"
        )
    if value.dtype != reference.dtype:
        raise ValueError(
            f"{name} has dtype {value.dtype} but the CPG network uses {reference.dtype}; "
            f"convert it with .to({reference.dtype})"
        )


# The amplitude equation of eq. 1 is a critically damped oscillator of natural frequency a/2.
# Integrated by eq. 2 with step dt, the error (r - rho, r_dot, r_ddot) is multiplied per step by
# a matrix whose spectral radius exceeds 1 once a dt > 1.528 ((3 - sqrt 5) * 2): the amplitude
# then grows without bound and the CPG outputs become NaN. PPO can push a (trained as
# exp(V_k), eq. 3) there with large learning rates, so a step uses a <= 1 / dt, where the
# radius is 0.78 (the scheme's fastest decay is 0.74, at a dt = 0.91); tests/cpg/test_network.py
# checks both numbers.
MAX_CONVERGENCE_STEP = 1.0


class CPGNetwork(nn.Module):
    """A batched, differentiable network of N coupled Hopf oscillators (paper eq. 1-3).

    The module owns only the trainable vector V (see :class:`Parametrisation`) and the time
    step; the CPG state is an input and an output of :meth:`forward`, never stored, so a
    rollout can save it and an update can replay one step from it (section III-B).

    Args:
        topology: which oscillator couples to which (Lambda).
        dt: integration time step in seconds (> 0).
        initial: physical initial values, see :class:`Parametrisation`.
        frozen: fields or entries that are not trained.
        ties: extra groups of entries sharing one trainable value.
        symmetric_coupling: tie w_ij = w_ji and phi_ji = -phi_ij for pairs coupled both ways.
        initial_phase: phase of each oscillator in :meth:`initial_state` (``(N,)`` or a
            scalar). Starting all phases equal with a phase bias of pi sits on an unstable
            equilibrium of the coupling, so presets start at their intended phase lags.
        check_inputs: validate shapes, dtypes, devices and finiteness on every call (a host
            sync on CUDA). Tensor inputs must have the network's dtype and device.
        dtype: floating dtype of the parameters (default: torch's default dtype).
        bounds: fields kept inside ``(low, high)`` by a sigmoid transform of V (see
            :class:`Parametrisation`).
    """

    def __init__(
        self,
        topology: Topology,
        dt: float,
        initial: Mapping[str, float | Sequence | Tensor],
        frozen: Mapping[str, bool | Sequence | Tensor] | None = None,
        ties: Iterable[Sequence[Entry]] = (),
        symmetric_coupling: bool = True,
        initial_phase: float | Sequence[float] = 0.0,
        check_inputs: bool = True,
        dtype: torch.dtype | None = None,
        bounds: Mapping[str, tuple] | None = None,
    ) -> None:
        super().__init__()
        if (
            isinstance(dt, bool)
            or not isinstance(dt, numbers.Real)
            or not (dt > 0 and math.isfinite(dt))
        ):
            raise ValueError(f"dt must be a positive finite number of seconds, got {dt!r}")
        ties = list(ties)
        if symmetric_coupling:
            ties += symmetric_coupling_ties(topology, frozen)
        self.topology = topology
        self.dt = float(dt)
        self.check_inputs = check_inputs
        dtype = dtype or torch.get_default_dtype()
        self.parametrisation = Parametrisation(topology, initial, frozen, ties, dtype, bounds)
        phase = torch.as_tensor(initial_phase, dtype=dtype)
        if phase.dim() > 1 or phase.numel() not in (1, topology.num_oscillators):
            raise ValueError(
                f"initial_phase must be a scalar or have {topology.num_oscillators} entries"
            )
        self.register_buffer("initial_phase", phase.expand(topology.num_oscillators).clone())

    @property
    def num_oscillators(self) -> int:
        return self.topology.num_oscillators

    @property
    def max_convergence(self) -> float:
        """The largest convergence rate ``a`` a step uses: ``MAX_CONVERGENCE_STEP / dt``."""
        return MAX_CONVERGENCE_STEP / self.dt

    def oscillator_parameters(
        self, drive: Tensor | float = 0.0, vector: Tensor | None = None
    ) -> OscillatorParameters:
        """The parameters of eq. 1 at ``drive``, the convergence rate ``a`` capped at
        :attr:`max_convergence` (eq. 2 diverges past ``a dt`` = 1.528; see
        ``MAX_CONVERGENCE_STEP``). Below the cap they are the parametrisation's, unchanged.
        ``vector``: a V other than the trained one, ``(M,)`` or one per batch row ``(B, M)``
        (the CPG-Actor's exploration in parameter space)."""
        params = self.parametrisation.oscillator_parameters(drive, vector)
        return params._replace(convergence=params.convergence.clamp(max=self.max_convergence))

    def initial_state(
        self,
        batch_size: int,
        amplitude: float | Tensor = 0.0,
        phase: float | Tensor | None = None,
    ) -> CPGState:
        """A state at rest (derivatives zero) on this module's device and dtype.

        ``phase`` defaults to the network's ``initial_phase``.
        """
        vector = self.parametrisation.vector
        if phase is None:
            phase = self.initial_phase
        return CPGState.initial(
            batch_size, self.num_oscillators, amplitude, phase, vector.dtype, vector.device
        )

    def forward(
        self,
        state: CPGState,
        drive: Tensor | float = 0.0,
        xi: Tensor | float = 0.0,
        kappa: Tensor | float = 0.0,
        vector: Tensor | None = None,
    ) -> tuple[CPGOutput, CPGState]:
        """One step: ``(state, drive, xi, kappa) -> (CPGOutput(x, x_dot), next_state)``;
        ``vector`` as in :meth:`oscillator_parameters`."""
        if self.check_inputs:
            self._validate(state, drive, xi, kappa)
        params = self.oscillator_parameters(drive, vector)
        return hopf_step(params, state, self.parametrisation.coupling, self.dt, xi, kappa)

    def _validate(self, state: CPGState, drive, xi, kappa) -> None:
        if not isinstance(state, CPGState):
            raise ValueError(f"state must be a CPGState, got {type(state).__name__}")
        n = self.num_oscillators
        reference = self.parametrisation.vector
        for name, value in zip(state._fields, state, strict=True):
            if not isinstance(value, Tensor):
                raise ValueError(f"state.{name} must be a torch.Tensor, got {type(value).__name__}")
        shape = state.phase.shape
        if len(shape) != 2 or shape[1] != n:
            raise ValueError(f"CPG state fields must have shape (B, {n}), got {tuple(shape)}")
        for name, value in zip(state._fields, state, strict=True):
            if value.shape != shape:
                raise ValueError(
                    f"state.{name} has shape {tuple(value.shape)}, expected {tuple(shape)}"
                )
            _check_like(f"state.{name}", value, reference)
            _check_finite(f"state.{name}", value)
        for name, value in (("drive", drive), ("xi", xi), ("kappa", kappa)):
            if isinstance(value, Tensor):
                if value.dim() > 0 and value.shape not in ((n,), shape):
                    raise ValueError(
                        f"{name} must be a scalar, ({n},) or {tuple(shape)}, "
                        f"got {tuple(value.shape)}"
                    )
                _check_like(name, value, reference)
            _check_finite(name, value)
        if (torch.as_tensor(drive) < 0).any():
            raise ValueError("drive must be >= 0 (nu and rho grow linearly with it)")

    def extra_repr(self) -> str:
        return (
            f"oscillators={self.topology.names}, edges={self.topology.edges}, dt={self.dt}, "
            f"trainable={self.parametrisation.num_parameters}"
        )
