"""Planar kinematics of ANYmal B's front leg, by hand: the hopper places its foot on the ground
and rewards with it, ANYmal B's foot-space pattern is built on it (the hind legs mirror it),
and the tests check the simulators on it. The functions take numpy arrays (float64) or JAX
arrays (the MJX backends call them inside ``jax.jit``;
:mod:`cpg_actor.robots.common.array_namespace`).

The leg moves in its sagittal (x-z) plane; y offsets change nothing here. A rotation by ``q``
about +y maps a vector ``(x, z)`` to ``(x cos q + z sin q, -x sin q + z cos q)``.
"""

from __future__ import annotations

import numpy as np

from cpg_actor.robots.anymal_leg import description as leg
from cpg_actor.robots.common.array_namespace import as_float, namespace


def rotate(angle, x, z):
    """``(x, z)`` turned by ``angle`` about +y."""
    xp = namespace(angle)
    c, s = xp.cos(angle), xp.sin(angle)
    return x * c + z * s, -x * s + z * c


HFE_ORIGIN = (leg.HFE_ORIGIN[0], leg.HFE_ORIGIN[2])  # (x, z) in the hip frame
KNEE_IN_THIGH = (leg.KFE_ORIGIN[0], leg.KFE_ORIGIN[2])
ADAPTER_IN_SHANK = (leg.ADAPTER_ORIGIN[0], leg.ADAPTER_ORIGIN[2])
FOOT_IN_SHANK = (
    ADAPTER_IN_SHANK[0] + leg.FOOT_CENTER[0],
    ADAPTER_IN_SHANK[1] + leg.FOOT_CENTER[2],
)


def knee_position(joint_pos: np.ndarray) -> np.ndarray:
    """KFE axis (x, z) in the hip frame, for joint positions ``(..., 2)`` (HFE, KFE)."""
    xp = namespace(joint_pos)
    q = as_float(xp, joint_pos)
    dx, dz = rotate(q[..., 0], *KNEE_IN_THIGH)
    return xp.stack([HFE_ORIGIN[0] + dx, HFE_ORIGIN[1] + dz], axis=-1)


def foot_position(joint_pos: np.ndarray) -> np.ndarray:
    """Centre of the foot sphere (x, z) in the hip frame, for joint positions ``(..., 2)``."""
    xp = namespace(joint_pos)
    q = as_float(xp, joint_pos)
    knee = knee_position(q)
    dx, dz = rotate(q[..., 0] + q[..., 1], *FOOT_IN_SHANK)
    return xp.stack([knee[..., 0] + dx, knee[..., 1] + dz], axis=-1)


def foot_velocity(joint_pos: np.ndarray, joint_vel: np.ndarray) -> np.ndarray:
    """Velocity (x, z) of the foot sphere centre relative to the hip, ``(..., 2)``."""
    xp = namespace(joint_pos, joint_vel)
    q, qd = as_float(xp, joint_pos), as_float(xp, joint_vel)
    a1, a12 = q[..., 0], q[..., 0] + q[..., 1]
    kx, kz = KNEE_IN_THIGH
    fx, fz = FOOT_IN_SHANK
    # d/dq R(q)(x, z) = (-x sin q + z cos q, -x cos q - z sin q)
    knee_dx = -kx * xp.sin(a1) + kz * xp.cos(a1)
    knee_dz = -kx * xp.cos(a1) - kz * xp.sin(a1)
    foot_dx = -fx * xp.sin(a12) + fz * xp.cos(a12)
    foot_dz = -fx * xp.cos(a12) - fz * xp.sin(a12)
    w1, w12 = qd[..., 0], qd[..., 0] + qd[..., 1]
    return xp.stack([knee_dx * w1 + foot_dx * w12, knee_dz * w1 + foot_dz * w12], axis=-1)
