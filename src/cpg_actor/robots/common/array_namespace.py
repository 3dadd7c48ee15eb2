"""The array module of a call's inputs: numpy, or ``jax.numpy`` for JAX arrays.

The hopper's pure functions (kinematics, reward terms, actuator law) are written once and run
on numpy arrays in the CPU simulators and on JAX arrays, inside ``jax.jit``, in the MJX
backend (:mod:`cpg_actor.robots.hopper.mjx`). Nothing here imports JAX unless it is given a JAX
array.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def is_jax(value: Any) -> bool:
    """A JAX array or a tracer (the arguments of a function being jitted)."""
    return type(value).__module__.split(".", 1)[0] in ("jax", "jaxlib")


def namespace(*values: Any):
    """``jax.numpy`` if any of ``values`` is a JAX array, else ``numpy``."""
    if any(is_jax(value) for value in values):
        import jax.numpy as jnp

        return jnp
    return np


def as_float(xp, value: Any):
    """``value`` as an array of ``xp``: float64 for numpy (the CPU simulators' precision), the
    array's own float type for JAX (float32 unless x64 is enabled)."""
    return np.asarray(value, dtype=np.float64) if xp is np else xp.asarray(value)
