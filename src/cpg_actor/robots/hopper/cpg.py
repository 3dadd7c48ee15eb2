"""The hopper's CPG: two coupled oscillators, hip (HFE) and knee (KFE)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import torch
from torch import Tensor

from cpg_actor.cpg.network import CPGNetwork
from cpg_actor.cpg.topology import Topology

HOPPER_JOINTS = ("HFE", "KFE")
# The nominal standing pose (legged_gym's ANYmal default), rad: the centre of oscillation.
HOPPER_NOMINAL_POSE = (0.4, -0.8)

# Initial CPG parameters of the hopper. The knee swings twice as far as the hip and in
# anti-phase (phi_HFE,KFE = pi), so that hip flexion and knee flexion happen together and the
# foot stays under the hip: a squat-and-extend motion at 2 Hz. Training reshapes all of it.
HOPPER_INITIAL = {
    "frequency": 2.0,  # Hz
    "amplitude": (0.15, 0.3),  # rad, HFE and KFE
    "convergence": 20.0,  # 1/s (Ijspeert et al. 2007 use 20)
    "coupling_weight": 10.0,
    "phase_bias": ((0.0, math.pi), (-math.pi, 0.0)),
}


def hopper_cpg(
    dt: float,
    initial: Mapping[str, float | Sequence | Tensor] | None = None,
    frozen: Mapping[str, bool | Sequence | Tensor] | None = None,
    check_inputs: bool = True,
    dtype: torch.dtype | None = None,
    bounds: Mapping[str, tuple] | None = None,
) -> CPGNetwork:
    """The hopper's CPG: HFE and KFE oscillators coupled both ways (w symmetric, phi antisymmetric).

    ``initial`` entries override :data:`HOPPER_INITIAL`. Trainable by default: frequency,
    amplitude and convergence per oscillator, one shared coupling weight and one phase bias
    (M = 8). Gains on the drive are frozen at 0: the hopper gets a constant drive.
    ``bounds``: fields kept inside ``(low, high)`` (:class:`Parametrisation`).
    """
    topology = Topology.all_to_all(2, names=HOPPER_JOINTS)
    return CPGNetwork(
        topology,
        dt=dt,
        initial={**HOPPER_INITIAL, **(initial or {})},
        frozen=frozen,
        symmetric_coupling=True,
        initial_phase=(0.0, math.pi),
        check_inputs=check_inputs,
        dtype=dtype,
        bounds=bounds,
    )
