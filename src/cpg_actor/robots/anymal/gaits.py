"""CPG presets for the ANYmal B quadruped: one oscillator per HFE and KFE joint, the classic gaits
as phase biases (paper eq. 1: the coupling term pulls theta_j - theta_i towards phi_ij).

Eight oscillators, per leg (LF, RF, LH, RH) one for HFE and one for KFE; the HAA joints are not
driven (held at the nominal pose by :class:`~cpg_actor.cpg.JointMap`). Coupling (Lambda):

* the four HFE oscillators all to all, with the gait's phase lags between the legs;
* each leg's KFE oscillator with its own HFE oscillator only.

Each oscillator has a target phase psi; every coupled pair gets ``phi_ij = psi_j - psi_i``, so
the network's phase-locked state is the gait, and the network starts in it. The leg phases
(fractions of a cycle, as in Ijspeert 2008 and the legged-robot CPG literature):

========  ====  ====  ====  ====
gait       LF    RF    LH    RH
========  ====  ====  ====  ====
trot       0    1/2   1/2    0     diagonal pairs in phase
pace       0    1/2    0    1/2    lateral pairs in phase
bound      0     0    1/2   1/2    front pair, then hind pair
pronk      0     0     0     0     all four together
walk       0    1/2   3/4   1/4    lateral-sequence walk: LF, RH, RF, LH
========  ====  ====  ====  ====

Within a leg the knee leads or lags the hip by a quarter cycle so that the foot lifts while
the hip swings forward (HFE decreasing, ``theta`` in (0, pi) for ``x = r cos theta``): the
front knees (nominal -0.8 rad) flex towards negative angles, so their ``x`` is lowest at
``theta_hip = pi/2``: ``psi_KFE = psi_HFE + pi/2``; the hind knees (nominal +0.8 rad) flex
towards positive angles: ``psi_KFE = psi_HFE - pi/2``.

The drive d of eq. 3 is the commanded forward speed (m/s): ``nu(d) = c_nu1 d + c_nu0`` and
``rho(d) = c_R1 d + c_R0``, so the step's frequency and length follow the command (the
CPG-Actor reads d from the observation, ``RobotSpec.drive_observation``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import torch
from torch import Tensor

from cpg_actor.cpg.joint_map import JointMap
from cpg_actor.cpg.network import CPGNetwork
from cpg_actor.cpg.topology import Topology

LEGS = ("LF", "RF", "LH", "RH")
OSCILLATORS = tuple(f"{leg}_{joint}" for leg in LEGS for joint in ("HFE", "KFE"))
# the joint (index in the quadruped's action order: per leg HAA, HFE, KFE) of each oscillator
OSCILLATOR_JOINTS = tuple(3 * leg + joint for leg in range(4) for joint in (1, 2))

GAITS: dict[str, tuple[float, float, float, float]] = {  # leg phase, fraction of a cycle
    "trot": (0.0, 0.5, 0.5, 0.0),
    "pace": (0.0, 0.5, 0.0, 0.5),
    "bound": (0.0, 0.0, 0.5, 0.5),
    "pronk": (0.0, 0.0, 0.0, 0.0),
    "walk": (0.0, 0.5, 0.75, 0.25),
}

# Initial parameters (eq. 3 with the drive d = the commanded forward speed, m/s): a 3 Hz step,
# hips +-(0.05 + 0.2 d) rad, knees +-(0.3 + 0.1 d) rad; convergence and coupling as the
# hopper's. Chosen on the open-loop trot (docs/quadruped.md, "The drive"): its forward speed
# grows with d (-0.08 m/s at d = 0 to 0.32 m/s at d = 1) and no robot falls. The gains are
# trained with the rest; with no drive (d = 0) the robot steps nearly in place.
QUADRUPED_INITIAL = {
    "frequency": 3.0,  # Hz, c_nu0
    "frequency_gain": 0.1,  # Hz per (m/s), c_nu1 (> 0 to be trainable)
    "amplitude": (0.05, 0.3) * 4,  # rad, c_R0 of HFE and KFE of each leg
    "amplitude_gain": (0.2, 0.1) * 4,  # rad per (m/s), c_R1
    "convergence": 20.0,  # 1/s
    "coupling_weight": 10.0,
}


def gait_phases(gait: str) -> tuple[float, ...]:
    """The target phase psi (rad) of each of the 8 oscillators for ``gait``."""
    if gait not in GAITS:
        raise ValueError(f"unknown gait {gait!r}; available: {', '.join(GAITS)}")
    phases = []
    for leg, fraction in zip(LEGS, GAITS[gait], strict=True):
        hip = 2.0 * math.pi * fraction
        knee_lead = math.pi / 2 if leg.endswith("F") else -math.pi / 2
        phases += [hip, hip + knee_lead]
    return tuple(phases)


def quadruped_topology() -> Topology:
    """Hips all to all, each knee with its own hip (both directions)."""
    hips = [2 * leg for leg in range(4)]
    edges = [(i, j) for i in hips for j in hips if i != j]
    edges += [(h, h + 1) for h in hips] + [(h + 1, h) for h in hips]
    return Topology(8, tuple(edges), OSCILLATORS)


def quadruped_cpg(
    dt: float,
    gait: str = "trot",
    initial: Mapping[str, float | Sequence | Tensor] | None = None,
    frozen: Mapping[str, bool | Sequence | Tensor] | None = None,
    check_inputs: bool = True,
    dtype: torch.dtype | None = None,
) -> CPGNetwork:
    """The quadruped's CPG in ``gait`` (module docstring), started in that gait's phases.

    ``initial`` entries override :data:`QUADRUPED_INITIAL` and the gait's phase biases.
    Trainable: as the hopper's, frequency, amplitude and convergence per oscillator, and per
    coupled pair one coupling weight and one phase bias (symmetric ties); and, unlike the
    hopper's, the drive gains c_nu1 and c_R1 of eq. 3 per oscillator. Step it with the drive
    ``d >= 0`` (the commanded forward speed in m/s) as ``cpg(state, d)``.
    """
    return _gait_network(quadruped_topology(), gait_phases(gait), QUADRUPED_INITIAL, dt,
                         initial, frozen, check_inputs, dtype)  # fmt: skip


# The ``leg`` layout (one oscillator per leg, a foot-space pattern:
# cpg_actor.robots.anymal.foot_space):
# 3 Hz as the joint layout; r is half the foot's step, m: 1 + 8 d cm (at 3 Hz and duty 1/2 a
# step of 2 r moves the body about 4 r f: 0.5 m/s at d = 0.5 with no slip).
LEG_INITIAL = {
    "frequency": 3.0,  # Hz, c_nu0
    "frequency_gain": 0.1,  # Hz per (m/s), c_nu1
    "amplitude": 0.01,  # m, c_R0
    "amplitude_gain": 0.08,  # m per (m/s), c_R1
    "convergence": 20.0,  # 1/s
    "coupling_weight": 10.0,
}


def quadruped_leg_cpg(
    dt: float,
    gait: str = "trot",
    initial: Mapping[str, float | Sequence | Tensor] | None = None,
    frozen: Mapping[str, bool | Sequence | Tensor] | None = None,
    check_inputs: bool = True,
    dtype: torch.dtype | None = None,
) -> CPGNetwork:
    """One oscillator per leg (LF, RF, LH, RH), coupled all to all with ``gait``'s phase lags
    and started in them; its amplitude is half the foot's step in metres
    (:class:`~cpg_actor.robots.anymal.foot_space.FootSpaceMap` turns phase and amplitude into
    joints). Trainable as :func:`quadruped_cpg`, the drive gains included."""
    if gait not in GAITS:
        raise ValueError(f"unknown gait {gait!r}; available: {', '.join(GAITS)}")
    psi = [2.0 * math.pi * fraction for fraction in GAITS[gait]]
    return _gait_network(Topology.all_to_all(4, names=LEGS), psi, LEG_INITIAL, dt, initial,
                         frozen, check_inputs, dtype)  # fmt: skip


def _gait_network(topology, psi, defaults, dt, initial, frozen, check_inputs, dtype) -> CPGNetwork:
    """A CPG started in the phases ``psi`` whose coupled pairs pull towards them
    (``phi_ij = psi_j - psi_i``), with the drive gains trainable."""
    n = topology.num_oscillators
    phase_bias = torch.zeros(n, n, dtype=torch.float64)
    for i, j in topology.edges:
        phase_bias[i, j] = psi[j] - psi[i]
    return CPGNetwork(
        topology,
        dt=dt,
        initial={**defaults, "phase_bias": phase_bias, **(initial or {})},
        frozen={"frequency_gain": False, "amplitude_gain": False, **(frozen or {})},
        symmetric_coupling=True,
        initial_phase=psi,
        check_inputs=check_inputs,
        dtype=dtype,
    )


def quadruped_joint_map(nominal_pose: Sequence[float]) -> JointMap:
    """HFE and KFE of every leg driven by their oscillators, HAA held at the nominal pose."""
    return JointMap(nominal_pose, joints=OSCILLATOR_JOINTS)


def open_loop_positions(
    gait: str, dt: float, nominal_pose: Sequence[float], num_robots: int, steps: int, drive: float
) -> Tensor:
    """The desired joint positions ``(steps, num_robots, 12)``, float64, of the ``gait``
    preset run open loop from its initial state at the constant drive ``drive`` (the
    commanded forward speed, m/s): no learning, no feedback, the same for every robot."""
    cpg = quadruped_cpg(dt, gait).double()
    joint_map = quadruped_joint_map(nominal_pose).double()
    state = cpg.initial_state(num_robots)
    drives = torch.full((num_robots, cpg.num_oscillators), float(drive), dtype=torch.float64)
    positions = []
    with torch.no_grad():
        for _ in range(steps):
            out, state = cpg(state, drives)
            positions.append(joint_map(out.position))
    return torch.stack(positions)
