"""cpg-actor: Central Pattern Generators trained with deep reinforcement learning.

Implements *CPG-Actor: Reinforcement Learning for Central Pattern Generators*
(Campanaro et al.): differentiable Hopf-oscillator CPGs used as the actor of PPO.
"""

__version__ = "0.1.0"

from cpg_actor.robots.registry import register as _register_envs

_register_envs()  # every robot's Gymnasium ids (cpg_actor/AnymalHopper-v0, cpg_actor/AnymalB-v0)


def __getattr__(name: str):
    """``cpg_actor.load_policy`` (:func:`cpg_actor.deploy.load_policy`), imported on first use:
    ``import cpg_actor`` stays free of torch."""
    if name == "load_policy":
        from cpg_actor.deploy import load_policy

        return load_policy
    raise AttributeError(f"module 'cpg_actor' has no attribute {name!r}")
