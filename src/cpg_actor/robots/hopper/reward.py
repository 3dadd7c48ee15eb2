"""The hopper's reward, paper eq. 4: five terms, weighted by c1 >= 0 and c2..c5 <= 0.

::

    r1 = (c1 * max(v_h, 0))^2            upward hip velocity: hop
    r2 = c2 * sum_j (p_d_j - p_m_j)^2    tracking error of the desired positions
    r3 = c3 * sum_j (v_m_j)^2            joint velocity
    r4 = c4 * sum_j (tau_d_j)^2          joint torque
    r5 = c5 * ||v_foot^{x,y}||           foot slip (the hip is on a rail: horizontal foot velocity)

The paper typesets r2..r4 as ``sum (c * x)^2``, which would make every penalty positive
whatever the sign of c; we read them as ``c * sum x^2`` so that c2..c4 <= 0 give penalties,
as the paper says they do. r1 is as printed (c1 >= 0, so the square only rescales it).

Beyond the paper, ``hop_reward="apex"`` replaces r1 with :func:`apex_reward`: the hop height,
paid once per flight at its apex. Eq. 4's r1 pays for upward hip speed anywhere in the cycle,
stance included, so its return and the hop height can come apart.
"""

from __future__ import annotations

import numpy as np

from cpg_actor.robots.common.array_namespace import namespace

REWARD_TERMS = ("r1", "r2", "r3", "r4", "r5")
REWARD_TERM_MEANING = {
    "r1": "upward hip velocity (c1 * max(v_h, 0))^2",
    "r2": "tracking error c2 * sum (p_d - p_m)^2",
    "r3": "joint velocity c3 * sum v_m^2",
    "r4": "joint torque c4 * sum tau_d^2",
    "r5": "foot slip c5 * |v_foot_xy|",
}


def reward_terms(
    weights: tuple[float, float, float, float, float],
    hip_velocity: np.ndarray,
    desired_position: np.ndarray,
    measured_position: np.ndarray,
    joint_velocity: np.ndarray,
    joint_torque: np.ndarray,
    foot_velocity_xy: np.ndarray,
) -> dict[str, np.ndarray]:
    """The five terms of eq. 4, batched: scalars ``(...)``, per-joint / x-y pairs ``(..., 2)``
    (numpy or JAX arrays: :mod:`cpg_actor.robots.common.array_namespace`)."""
    c1, c2, c3, c4, c5 = weights
    xp = namespace(hip_velocity, measured_position, joint_torque)
    return {
        "r1": xp.square(c1 * xp.maximum(hip_velocity, 0.0)),
        "r2": c2 * xp.sum(xp.square(desired_position - measured_position), axis=-1),
        "r3": c3 * xp.sum(xp.square(joint_velocity), axis=-1),
        "r4": c4 * xp.sum(xp.square(joint_torque), axis=-1),
        "r5": c5 * xp.linalg.norm(foot_velocity_xy, axis=-1),
    }


AIRBORNE = 1e-3  # m: the foot's lowest point above the ground (contacts penetrate slightly)


def apex_reward(
    weight: float,
    com_velocity_before: np.ndarray,
    com_velocity: np.ndarray,
    com_height: np.ndarray,
    highest_standing_com: float,
    foot_height: np.ndarray,
) -> np.ndarray:
    """``weight * max(com_height - highest_standing_com, 0)`` at a flight's apex, else 0.

    The apex is the control step in which the vertical velocity of the robot's centre of mass
    turns from up (``com_velocity_before > 0``) to down (``com_velocity <= 0``) with the foot
    in the air (its lowest point above ``AIRBORNE``). In flight the centre of mass follows a
    parabola whatever the joints do, so each flight has one apex and pays once; its height is
    paid above the highest any standing pose lifts it, so only a real hop pays. Simpler forms
    are gamed: paying the hip's height above its standing height rewards chattering on a
    straightened leg; paying the foot's clearance at each turn of the hip's velocity rewards
    swinging the leg in flight to turn the hip many times per flight."""
    xp = namespace(com_velocity, com_height)
    apex = (com_velocity_before > 0.0) & (com_velocity <= 0.0) & (foot_height > AIRBORNE)
    return xp.where(apex, weight * xp.maximum(com_height - highest_standing_com, 0.0), 0.0)


def total_reward(terms: dict[str, np.ndarray]) -> np.ndarray:
    """r = r1 + r2 + r3 + r4 + r5."""
    return terms["r1"] + terms["r2"] + terms["r3"] + terms["r4"] + terms["r5"]
