"""CPG presets for a quadruped: the classic gaits as phase biases (paper eq. 1: the coupling term
pulls theta_j - theta_i towards phi_ij), for any robot whose legs are each a hip (abduction),
a hip flexion and a knee joint, in that order.

Two layouts. ``joint``: eight oscillators, per leg one for the hip flexion and one for the
knee; the abduction joints are not driven (held at the nominal pose by
:class:`~cpg_actor.cpg.JointMap`). Coupling (Lambda):

* the four hip oscillators all to all, with the gait's phase lags between the legs;
* each leg's knee oscillator with its own hip oscillator only.

``leg``: one oscillator per leg, all to all with the gait's lags, driving a foot-space pattern
(:mod:`cpg_actor.robots.common.quadruped.foot_space`) on the robot's leg.

Each oscillator has a target phase psi; every coupled pair gets ``phi_ij = psi_j - psi_i``, so
the network's phase-locked state is the gait, and the network starts in it. The leg phases by
the leg's place on the body (fractions of a cycle, as in Ijspeert 2008 and the legged-robot
CPG literature; L/R left/right, F/H front/hind):

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
the hip swings forward (hip angle decreasing, ``theta`` in (0, pi) for ``x = r cos theta``): a
knee that flexes towards negative angles (ANYmal's front knees, all of the Go1's) has its
``x`` lowest at ``theta_hip = pi/2``: ``psi_knee = psi_hip + pi/2``; a knee that flexes towards
positive angles (ANYmal's hind knees): ``psi_knee = psi_hip - pi/2``. A robot says which
(:attr:`GaitCPGs.knee_signs`).

The drive d of eq. 3 is the commanded forward speed (m/s): ``nu(d) = c_nu1 d + c_nu0`` and
``rho(d) = c_R1 d + c_R0``, so the step's frequency and length follow the command (the
CPG-Actor reads d from the observation, ``RobotSpec.drive_observation``). With planar steps
(the ``leg`` layout, ``agent_config.cpg_planar_steps``) each leg's drive is its foot's
commanded planar speed and its step points along it
(:mod:`cpg_actor.robots.common.quadruped.planar_drive`): the whole command, turning and side
steps included.

A robot's presets are one :class:`GaitCPGs`: its legs, where each is on the body, which way
each knee flexes, its leg's lengths for the foot-space pattern (its ``gaits.py``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import torch
from torch import Tensor

from cpg_actor.cpg.joint_map import JointMap
from cpg_actor.cpg.network import CPGNetwork
from cpg_actor.cpg.topology import Topology
from cpg_actor.robots.common.quadruped.foot_space import FootSpacePattern, Vec2
from cpg_actor.robots.common.quadruped.planar_drive import PlanarDrive
from cpg_actor.robots.plugin import CPGLayout

PLACES = ("LF", "RF", "LH", "RH")  # the columns of GAITS
GAITS: dict[str, tuple[float, float, float, float]] = {  # leg phase, fraction of a cycle
    "trot": (0.0, 0.5, 0.5, 0.0),
    "pace": (0.0, 0.5, 0.0, 0.5),
    "bound": (0.0, 0.0, 0.5, 0.5),
    "pronk": (0.0, 0.0, 0.0, 0.0),
    "walk": (0.0, 0.5, 0.75, 0.25),
}
# the joint (index in the action order: per leg abduction, hip, knee) of each oscillator of
# the joint layout
OSCILLATOR_JOINTS = tuple(3 * leg + joint for leg in range(4) for joint in (1, 2))

# Initial parameters (eq. 3 with the drive d = the commanded forward speed, m/s), chosen on
# ANYmal B. The joint layout: a 3 Hz step, hips +-(0.05 + 0.2 d) rad, knees +-(0.3 + 0.1 d) rad;
# convergence and coupling as the hopper's. Chosen on the open-loop trot (docs/quadruped.md, "The
# drive"): its forward speed grows with d (-0.08 m/s at d = 0 to 0.32 m/s at d = 1) and no robot
# falls; with no drive (d = 0) the robot steps nearly in place. The gains are trained with the
# rest. (The Go1 takes them as they are: its shorter leg takes a proportionally shorter step at
# the same angles.)
JOINT_INITIAL = {
    "frequency": 3.0,  # Hz, c_nu0
    "frequency_gain": 0.1,  # Hz per (m/s), c_nu1 (> 0 to be trainable)
    "amplitude": (0.05, 0.3) * 4,  # rad, c_R0 of the hip and the knee of each leg
    "amplitude_gain": (0.2, 0.1) * 4,  # rad per (m/s), c_R1
    "convergence": 20.0,  # 1/s
    "coupling_weight": 10.0,
}
# The leg layout: 3 Hz as the joint layout; r is half the foot's step, m: 1 + 8 d cm (at 3 Hz and
# duty 1/2 a step of 2 r moves the body about 4 r f: 0.5 m/s at d = 0.5 with no slip; the step a
# speed needs does not depend on the leg).
LEG_INITIAL = {
    "frequency": 3.0,  # Hz, c_nu0
    "frequency_gain": 0.1,  # Hz per (m/s), c_nu1
    "amplitude": 0.01,  # m, c_R0
    "amplitude_gain": 0.08,  # m per (m/s), c_R1
    "convergence": 20.0,  # 1/s
    "coupling_weight": 10.0,
}


def leg_phase(gait: str, place: str) -> float:
    """The phase (fraction of a cycle) of the leg at ``place`` (one of :data:`PLACES`)."""
    if gait not in GAITS:
        raise ValueError(f"unknown gait {gait!r}; available: {', '.join(GAITS)}")
    return GAITS[gait][PLACES.index(place)]


@dataclass(frozen=True)
class GaitCPGs:
    """The gait CPGs of one robot: its legs in joint order, where each is on the body, which way
    each knee flexes, its leg for the foot-space pattern, and the initial parameters of each
    layout (eq. 3, the drive d the commanded forward speed in m/s; keys as
    :class:`~cpg_actor.cpg.CPGNetwork`'s ``initial``). Its methods are the robot's CPG presets;
    :meth:`layouts` are its ``Robot.cpg_layouts``."""

    legs: tuple[str, ...]  # the robot's leg names, in joint order
    places: tuple[str, ...]  # each leg's place on the body, one of PLACES
    joints: tuple[str, str]  # the names of a leg's hip and knee joint (the oscillators')
    knee_signs: tuple[int, ...]  # -1: the knee flexes towards negative angles, +1: positive
    # the front leg in its sagittal plane (x, z; m): the knee in the thigh frame relative to the
    # hip flexion axis, the foot centre in the shank frame relative to the knee axis
    thigh: Vec2
    shank: Vec2
    clearance: float  # m: the foot's lift at mid swing in the foot-space pattern
    penetration: float = 0.01  # m: how far the stance foot is pressed below its nominal height
    # the planar steps' geometry (the leg layout's planar drive, agent_config.cpg_planar_steps):
    # each foot's nominal place (x, y) in the base frame (m, leg order; the yaw rate moves the
    # base above it at w x (x, y)), and the foot's lateral distance from its abduction axis (m,
    # outwards). Empty: forward steps only
    feet: tuple[Vec2, ...] = ()
    abduction_offset: float = 0.0
    joint_initial: Mapping[str, float | Sequence] = field(default_factory=lambda: JOINT_INITIAL)
    leg_initial: Mapping[str, float | Sequence] = field(default_factory=lambda: LEG_INITIAL)

    @property
    def oscillators(self) -> tuple[str, ...]:
        return tuple(f"{leg}_{joint}" for leg in self.legs for joint in self.joints)

    def footfalls(self) -> dict[str, tuple[float, ...]]:
        """Each gait's leg phases (fractions of a cycle) in the robot's leg order."""
        return {gait: tuple(leg_phase(gait, place) for place in self.places) for gait in GAITS}

    def layouts(self) -> dict[str, CPGLayout]:
        """The robot's CPG layouts: ``joint`` (the default) and ``leg``."""
        gaits = self.footfalls()
        planar = self.planar_drive if self.feet else None
        return {
            "joint": CPGLayout(self.joint_cpg, joints=OSCILLATOR_JOINTS, gaits=gaits),
            "leg": CPGLayout(
                self.leg_cpg, pattern=self.foot_space, gaits=gaits, planar_drive=planar
            ),
        }

    def foot_space(self, nominal_pose: Sequence[float]) -> FootSpacePattern:
        """The ``leg`` layout's pattern on the robot's leg, around ``nominal_pose`` (with
        planar steps where the robot gives its feet)."""
        lateral = None
        if self.feet:
            lateral = [math.copysign(self.abduction_offset, y) for _, y in self.feet]
        return FootSpacePattern(nominal_pose, self.thigh, self.shank, self.clearance,
                                self.penetration, lateral)  # fmt: skip

    def planar_drive(self) -> PlanarDrive:
        """The ``leg`` layout's drive from the whole command (:mod:`planar_drive
        <cpg_actor.robots.common.quadruped.planar_drive>`)."""
        return PlanarDrive(self.feet)

    def gait_phases(self, gait: str) -> tuple[float, ...]:
        """The target phase psi (rad) of each of the joint layout's 8 oscillators in ``gait``."""
        phases = []
        for place, sign in zip(self.places, self.knee_signs, strict=True):
            hip = 2.0 * math.pi * leg_phase(gait, place)
            phases += [hip, hip - sign * math.pi / 2]
        return tuple(phases)

    def topology(self) -> Topology:
        """Hips all to all, each knee with its own hip (both directions)."""
        hips = [2 * leg for leg in range(4)]
        edges = [(i, j) for i in hips for j in hips if i != j]
        edges += [(h, h + 1) for h in hips] + [(h + 1, h) for h in hips]
        return Topology(8, tuple(edges), self.oscillators)

    def joint_cpg(
        self,
        dt: float,
        gait: str = "trot",
        initial: Mapping[str, float | Sequence | Tensor] | None = None,
        frozen: Mapping[str, bool | Sequence | Tensor] | None = None,
        check_inputs: bool = True,
        dtype: torch.dtype | None = None,
    ) -> CPGNetwork:
        """The ``joint`` layout's CPG in ``gait`` (module docstring), started in that gait's
        phases. ``initial`` entries override :attr:`joint_initial` and the gait's phase biases.
        Trainable: as the hopper's, frequency, amplitude and convergence per oscillator, and per
        coupled pair one coupling weight and one phase bias (symmetric ties); and, unlike the
        hopper's, the drive gains c_nu1 and c_R1 of eq. 3 per oscillator. Step it with the
        drive ``d >= 0`` (the commanded forward speed in m/s) as ``cpg(state, d)``."""
        return _gait_network(self.topology(), self.gait_phases(gait), self.joint_initial, dt,
                             initial, frozen, check_inputs, dtype)  # fmt: skip

    def leg_cpg(
        self,
        dt: float,
        gait: str = "trot",
        initial: Mapping[str, float | Sequence | Tensor] | None = None,
        frozen: Mapping[str, bool | Sequence | Tensor] | None = None,
        check_inputs: bool = True,
        dtype: torch.dtype | None = None,
    ) -> CPGNetwork:
        """One oscillator per leg, coupled all to all with ``gait``'s phase lags and started in
        them; its amplitude is half the foot's step in metres (the foot-space pattern turns
        phase and amplitude into joints). Trainable as :meth:`joint_cpg`."""
        psi = [2.0 * math.pi * leg_phase(gait, place) for place in self.places]
        return _gait_network(Topology.all_to_all(4, names=self.legs), psi, self.leg_initial,
                             dt, initial, frozen, check_inputs, dtype)  # fmt: skip

    def open_loop_positions(
        self,
        gait: str,
        dt: float,
        nominal_pose: Sequence[float],
        num_robots: int,
        steps: int,
        drive: float,
    ) -> Tensor:
        """The desired joint positions ``(steps, num_robots, 12)``, float64, of the ``gait``
        preset (joint layout) run open loop from its initial state at the constant drive
        ``drive`` (the commanded forward speed, m/s): no learning, no feedback, the same for
        every robot."""
        cpg = self.joint_cpg(dt, gait).double()
        joint_map = joint_map_for(nominal_pose).double()
        state = cpg.initial_state(num_robots)
        drives = torch.full((num_robots, cpg.num_oscillators), float(drive), dtype=torch.float64)
        positions = []
        with torch.no_grad():
            for _ in range(steps):
                out, state = cpg(state, drives)
                positions.append(joint_map(out.position))
        return torch.stack(positions)


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


def joint_map_for(nominal_pose: Sequence[float]) -> JointMap:
    """The joint layout's map: hip and knee of every leg driven by their oscillators,
    abduction held at the nominal pose."""
    return JointMap(nominal_pose, joints=OSCILLATOR_JOINTS)
