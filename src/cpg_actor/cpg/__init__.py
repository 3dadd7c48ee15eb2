"""Differentiable Hopf-oscillator CPG networks (paper section III-A, eq. 1-3) and the joint
map from their outputs to joint positions. Knows no robot: each robot's CPG presets live in
its folder (:mod:`cpg_actor.robots`)."""

from cpg_actor.cpg.hopf import (
    CPGOutput,
    CPGState,
    OscillatorParameters,
    amplitude_acceleration,
    coupling_term,
    hopf_step,
    phase_velocity,
)
from cpg_actor.cpg.joint_map import JointMap
from cpg_actor.cpg.network import CPGNetwork
from cpg_actor.cpg.parametrisation import FIELDS, Parametrisation, symmetric_coupling_ties
from cpg_actor.cpg.topology import Topology

__all__ = [
    "CPGNetwork",
    "CPGOutput",
    "CPGState",
    "FIELDS",
    "JointMap",
    "OscillatorParameters",
    "Parametrisation",
    "Topology",
    "amplitude_acceleration",
    "coupling_term",
    "hopf_step",
    "phase_velocity",
    "symmetric_coupling_ties",
]
