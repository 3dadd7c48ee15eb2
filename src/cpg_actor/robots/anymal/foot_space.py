"""One oscillator per leg driving a foot-space pattern (the quadruped's ``leg`` layout).

Each leg's oscillator (phase theta, amplitude r, eq. 1-2) sets where that leg's foot should be,
in the leg's sagittal plane, around the foot's place in the nominal pose (x forward, z up, m):

    dx = -r cos(theta)                                   (the step: r is half its length)
    dz = clearance sin(theta)    if sin(theta) > 0        (swing: the foot lifts)
         penetration sin(theta)  otherwise                (stance: it presses down)

so the foot swings forward while theta goes from 0 to pi and pushes back on the ground from
pi to 2 pi: the pattern of Bellegarda and Ijspeert's CPG-RL (2022), here driven by this
project's Hopf oscillators. The HFE and KFE angles that put the foot there come from the leg's
planar inverse kinematics (the same leg as the hopper's, :mod:`cpg_actor.robots.hopper.kinematics`;
the hind legs are the front legs mirrored front to back, so they solve the mirrored target and
negate the angles). HAA stays at the nominal pose. Differentiable in theta and r (torch).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch
from torch import Tensor, nn

from cpg_actor.robots.hopper import kinematics

# the leg (front, in its own sagittal plane; m): the knee in the thigh frame, the foot centre in
# the shank frame, both relative to the joint before them; the HFE axis in the hip frame
THIGH = kinematics.KNEE_IN_THIGH
SHANK = kinematics.FOOT_IN_SHANK
HFE_ORIGIN = kinematics.HFE_ORIGIN
CLEARANCE = 0.08  # m: the foot's lift at mid swing (CPG-RL's ground clearance, ANYmal-sized)
PENETRATION = 0.01  # m: how far the stance foot is pressed below its nominal height


def _rotate(angle: Tensor, x, z) -> tuple[Tensor, Tensor]:
    """Rotation about +y: ``(x, z) -> (x cos q + z sin q, -x sin q + z cos q)``."""
    c, s = torch.cos(angle), torch.sin(angle)
    return x * c + z * s, -x * s + z * c


def front_leg_foot(hfe: Tensor, kfe: Tensor) -> tuple[Tensor, Tensor]:
    """Forward kinematics: the foot centre (x, z) relative to the HFE axis, front leg."""
    kx, kz = _rotate(hfe, *THIGH)
    fx, fz = _rotate(hfe + kfe, *SHANK)
    return kx + fx, kz + fz


class FootSpaceMap(nn.Module):
    """``(phase, amplitude)`` of 4 leg oscillators ``(B, 4)`` (LF, RF, LH, RH) -> desired joint
    positions ``(B, 12)`` (per leg HAA, HFE, KFE), by the pattern and inverse kinematics of the
    module docstring.

    Args:
        nominal_pose: the robot's 12 nominal joint positions (HAA 0; the front legs' HFE and
            KFE, the hind legs' the mirror image of them).
        clearance, penetration: the swing lift and the stance press, m.
    """

    def __init__(
        self,
        nominal_pose: Sequence[float],
        clearance: float = CLEARANCE,
        penetration: float = PENETRATION,
    ) -> None:
        super().__init__()
        pose = torch.as_tensor(nominal_pose, dtype=torch.float64).reshape(4, 3)
        front = pose[0, 1:]
        # the hind legs' sign: their HFE and KFE mirror the front legs' (x flipped)
        signs = torch.where(pose[:, 1] * front[0] >= 0, 1.0, -1.0)
        if not torch.allclose(pose[:, 1:] * signs[:, None], front.expand(4, 2)):
            raise ValueError("FootSpaceMap needs legs that are the front leg or its mirror image")
        self.register_buffer("offset", pose.reshape(-1).clone())
        self.register_buffer("signs", signs)
        x0, z0 = front_leg_foot(front[0], front[1])
        self.register_buffer("foot", torch.stack([x0, z0]))  # the nominal foot (front leg)
        self.clearance = float(clearance)
        self.penetration = float(penetration)
        # the knee solution: cos(kfe - phi) = k; the branch (+ or -) of the nominal pose
        (t1x, t1z), (a, b) = THIGH, SHANK
        self._A, self._B = t1x * a + t1z * b, t1x * b - t1z * a
        self._rho = math.hypot(self._A, self._B)
        self._phi = math.atan2(self._B, self._A)
        self._lengths = t1x**2 + t1z**2 + a**2 + b**2
        self._branch = 1.0 if math.sin(float(front[1]) - self._phi) >= 0 else -1.0

    def inverse_kinematics(self, x: Tensor, z: Tensor) -> tuple[Tensor, Tensor]:
        """HFE, KFE of a front leg whose foot centre is at (x, z) from the HFE axis (beyond
        reach: the leg straightened towards it)."""
        k = ((x * x + z * z - self._lengths) / (2.0 * self._rho)).clamp(-1.0 + 1e-6, 1.0 - 1e-6)
        kfe = self._phi + self._branch * torch.acos(k)
        (t1x, t1z), (a, b) = THIGH, SHANK
        wx, wz = _rotate(kfe, a, b)
        wx, wz = wx + t1x, wz + t1z
        hfe = torch.atan2(wz, wx) - torch.atan2(z, x)
        hfe = torch.atan2(torch.sin(hfe), torch.cos(hfe))  # within (-pi, pi]
        return hfe, kfe

    def forward(self, phase: Tensor, amplitude: Tensor) -> Tensor:
        s = torch.sin(phase)
        dx = -amplitude * torch.cos(phase)
        dz = torch.where(s > 0, self.clearance * s, self.penetration * s)
        signs = self.signs.to(phase.dtype)
        # the target in the front leg's frame (the hind legs' mirrored front to back)
        x = self.foot[0].to(phase.dtype) + signs * dx
        z = self.foot[1].to(phase.dtype) + dz
        hfe, kfe = self.inverse_kinematics(x, z)
        haa = self.offset.to(phase.dtype)[0::3].expand_as(hfe)
        joints = torch.stack([haa, signs * hfe, signs * kfe], dim=-1)  # (B, 4, 3)
        return joints.reshape(*phase.shape[:-1], 12)
