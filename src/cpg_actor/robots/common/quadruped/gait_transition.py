"""A change of gait at run time: a running gait CPG (either layout, trained or not) moves from
its gait to another while it keeps stepping, with no jump in any joint command.

The gait is the phase biases phi_ij of eq. 1 (``gaits.py``): the coupling pulls each phase
difference theta_j - theta_i towards phi_ij. Setting them to the new gait's at once leaves the
legs where they are when a lag must change by half a cycle (trot to pace, trot to bound):
sin(pi) = 0, an equilibrium the coupling does not leave. So a transition moves the phase biases
a share of the way at each control step, from the CPG's own to the new gait's, over ``steps``
steps (a moving equilibrium the phases follow); every other parameter (trained frequencies,
amplitudes, gains, weights) and the state are kept. The legs settle into the new lags over the
next cycles, as fast as the coupling weight and the amplitudes let them.
"""

from __future__ import annotations

import torch

from cpg_actor.cpg.network import CPGNetwork
from cpg_actor.robots.common.quadruped.gaits import GaitCPGs


class GaitTransition:
    """Moves ``cpg``'s phase biases to ``gait``'s over ``steps`` calls of :meth:`step` (one a
    control step; module docstring). ``gaits``: the robot's gait CPGs (``cpg`` one of its
    layouts, its phase biases trainable as the presets make them)."""

    def __init__(self, gaits: GaitCPGs, cpg: CPGNetwork, gait: str, steps: int) -> None:
        if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
            raise ValueError(f"steps must be an integer >= 1, got {steps!r}")
        layouts = {4: gaits.leg_cpg, 8: gaits.joint_cpg}
        if cpg.num_oscillators not in layouts:
            raise ValueError(f"not a gait CPG of this robot: {cpg.num_oscillators} oscillators "
                             "(the leg layout has 4, the joint layout 8)")  # fmt: skip
        vector = cpg.parametrisation.vector
        target = layouts[cpg.num_oscillators](cpg.dt, gait, dtype=vector.dtype).parametrisation
        index = cpg.parametrisation.indices("phase_bias")
        trained = index >= 0
        if trained.sum() == 0 or not torch.equal(index, target.indices("phase_bias")):
            raise ValueError("a gait transition needs the CPG's phase biases trainable, as the "
                             "robot's presets make them")  # fmt: skip
        self.cpg, self.steps, self.taken = cpg, steps, 0
        self.index = index[trained]
        self.start = vector.detach()[self.index].clone()
        self.end = target.vector.detach()[self.index].to(vector.device)

    @property
    def done(self) -> bool:
        return self.taken >= self.steps

    def step(self) -> None:
        """The phase biases one step further (at the new gait's after ``steps`` calls)."""
        self.taken = min(self.taken + 1, self.steps)
        share = self.taken / self.steps
        with torch.no_grad():
            self.cpg.parametrisation.vector[self.index] = self.start + share * (
                self.end - self.start
            )
