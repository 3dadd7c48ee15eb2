"""Differentiable Hopf-oscillator CPG networks (paper section III-A, eq. 1-3)."""

from cpg_actor.cpg.hopf import (
    CPGOutput,
    CPGState,
    OscillatorParameters,
    amplitude_acceleration,
    coupling_term,
    hopf_step,
    phase_velocity,
)
from cpg_actor.cpg.network import CPGNetwork
from cpg_actor.cpg.parametrisation import FIELDS, Parametrisation, symmetric_coupling_ties
from cpg_actor.cpg.presets import (
    HOPPER_INITIAL,
    HOPPER_JOINTS,
    HOPPER_NOMINAL_POSE,
    JointMap,
    hopper_cpg,
)
from cpg_actor.cpg.topology import Topology

__all__ = [
    "CPGNetwork",
    "CPGOutput",
    "CPGState",
    "FIELDS",
    "HOPPER_INITIAL",
    "HOPPER_JOINTS",
    "HOPPER_NOMINAL_POSE",
    "JointMap",
    "OscillatorParameters",
    "Parametrisation",
    "Topology",
    "amplitude_acceleration",
    "coupling_term",
    "hopf_step",
    "hopper_cpg",
    "phase_velocity",
    "symmetric_coupling_ties",
]
