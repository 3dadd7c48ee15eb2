"""A trained policy outside training: loaded from its run (:func:`load_policy`) and exported
as one self-contained file for a robot's control loop (:mod:`cpg_actor.deploy.export`)."""

from cpg_actor.deploy.load import load_policy
from cpg_actor.training.policy import Policy, PolicyStep

__all__ = ["Policy", "PolicyStep", "load_policy"]
