"""One oscillator per leg driving a foot-space pattern (the quadruped's ``leg`` layout).

Each leg's oscillator (phase theta, amplitude r, eq. 1-2) sets where that leg's foot should be,
in the leg's sagittal plane, around the foot's place in the nominal pose (x forward, z up, m):

    dx = -r cos(theta)                                   (the step: r is half its length)
    dz = clearance sin(theta)    if sin(theta) > 0        (swing: the foot lifts)
         penetration sin(theta)  otherwise                (stance: it presses down)

so the foot swings forward while theta goes from 0 to pi and pushes back on the ground from
pi to 2 pi: the pattern of Bellegarda and Ijspeert's CPG-RL (2022), here driven by this
project's Hopf oscillators. The hip and knee angles that put the foot there come from the leg's
planar inverse kinematics (a robot gives its thigh and shank; legs that are the front legs
mirrored front to back, as ANYmal's hind legs, solve the mirrored target and negate the angles).
The abduction joint stays at the nominal pose. Differentiable in theta and r (torch).

Planar steps (:mod:`cpg_actor.robots.common.quadruped.planar_drive`): with a step direction
psi per leg (rad from forward, in the base frame), the step lies in the ground plane,

    (dx, dy) = -r cos(theta) (cos psi, sin psi)            (dz as above)

and the abduction joint puts the foot's lateral place: the leg turned about its abduction axis
(+x) by q carries the foot, at the lateral distance l from that axis (``lateral``) and the
height z below it, to (l cos q - z sin q, l sin q + z cos q); for the target (Y, Z) the leg's
own height is ``z = -sqrt(Y^2 + Z^2 - l^2)`` and ``q = atan2(Z, Y) - atan2(z, l)`` (the
nominal abduction 0, the hip flexion axis at the abduction axis' height, as on ANYmal B and
the Go1), and the sagittal inverse kinematics solves (x, z).

A robot's pattern is this one on its leg (its
:class:`~cpg_actor.robots.common.quadruped.gaits.GaitCPGs`: ``foot_space(nominal_pose)``, the
``pattern`` of its ``leg`` CPG layout).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch
from torch import Tensor, nn

Vec2 = tuple[float, float]


def _rotate(angle: Tensor, x, z) -> tuple[Tensor, Tensor]:
    """Rotation about +y: ``(x, z) -> (x cos q + z sin q, -x sin q + z cos q)``."""
    c, s = torch.cos(angle), torch.sin(angle)
    return x * c + z * s, -x * s + z * c


def leg_foot(hip: Tensor, knee: Tensor, thigh: Vec2, shank: Vec2) -> tuple[Tensor, Tensor]:
    """Forward kinematics: the foot centre (x, z) relative to the hip flexion axis, front leg
    (``thigh``: the knee in the thigh frame, ``shank``: the foot centre in the shank frame)."""
    kx, kz = _rotate(hip, *thigh)
    fx, fz = _rotate(hip + knee, *shank)
    return kx + fx, kz + fz


class FootSpacePattern(nn.Module):
    """``(phase, amplitude)`` of 4 leg oscillators ``(B, 4)`` (the robot's legs in joint order)
    -> desired joint positions ``(B, 12)`` (per leg abduction, hip, knee), by the pattern and
    inverse kinematics of the module docstring.

    Args:
        nominal_pose: the robot's 12 nominal joint positions (each leg's hip and knee those of
            the first leg or their mirror image).
        thigh: the knee in the thigh frame (x, z), m, relative to the hip flexion axis.
        shank: the foot centre in the shank frame (x, z), m, relative to the knee axis.
        clearance, penetration: the swing lift and the stance press, m.
        lateral: each leg's foot's lateral distance from its abduction axis, m (+ left), for
            planar steps; None: forward steps only.
    """

    def __init__(
        self,
        nominal_pose: Sequence[float],
        thigh: Vec2,
        shank: Vec2,
        clearance: float,
        penetration: float,
        lateral: Sequence[float] | None = None,
    ) -> None:
        super().__init__()
        self.thigh, self.shank = tuple(thigh), tuple(shank)
        pose = torch.as_tensor(nominal_pose, dtype=torch.float64).reshape(4, 3)
        front = pose[0, 1:]
        # the hind legs' sign: their HFE and KFE mirror the front legs' (x flipped)
        signs = torch.where(pose[:, 1] * front[0] >= 0, 1.0, -1.0)
        if not torch.allclose(pose[:, 1:] * signs[:, None], front.expand(4, 2)):
            raise ValueError(
                f"{type(self).__name__} needs legs that are the front leg or its mirror image"
            )
        self.register_buffer("offset", pose.reshape(-1).clone())
        self.register_buffer("signs", signs)
        self.planar = lateral is not None
        if self.planar:
            if len(lateral) != 4 or torch.any(pose[:, 0] != 0):
                raise ValueError(f"{type(self).__name__}'s planar steps need 4 lateral offsets "
                                 f"and a nominal abduction of 0, got {list(lateral)}")  # fmt: skip
            # the robot's geometry, not learned: out of the state dict, so that checkpoints
            # from before planar steps load
            lateral = torch.as_tensor(lateral, dtype=torch.float64)
            self.register_buffer("lateral", lateral, persistent=False)
        x0, z0 = leg_foot(front[0], front[1], self.thigh, self.shank)
        self.register_buffer("foot", torch.stack([x0, z0]))  # the nominal foot (front leg)
        self.clearance = float(clearance)
        self.penetration = float(penetration)
        # the knee solution: cos(kfe - phi) = k; the branch (+ or -) of the nominal pose
        (t1x, t1z), (a, b) = self.thigh, self.shank
        self._A, self._B = t1x * a + t1z * b, t1x * b - t1z * a
        self._rho = math.hypot(self._A, self._B)
        self._phi = math.atan2(self._B, self._A)
        self._lengths = t1x**2 + t1z**2 + a**2 + b**2
        self._branch = 1.0 if math.sin(float(front[1]) - self._phi) >= 0 else -1.0

    def inverse_kinematics(self, x: Tensor, z: Tensor) -> tuple[Tensor, Tensor]:
        """Hip and knee of a front leg whose foot centre is at (x, z) from the hip flexion axis
        (beyond reach: the leg straightened towards it)."""
        k = ((x * x + z * z - self._lengths) / (2.0 * self._rho)).clamp(-1.0 + 1e-6, 1.0 - 1e-6)
        kfe = self._phi + self._branch * torch.acos(k)
        (t1x, t1z), (a, b) = self.thigh, self.shank
        wx, wz = _rotate(kfe, a, b)
        wx, wz = wx + t1x, wz + t1z
        hfe = torch.atan2(wz, wx) - torch.atan2(z, x)
        hfe = torch.atan2(torch.sin(hfe), torch.cos(hfe))  # within (-pi, pi]
        return hfe, kfe

    def forward(self, phase: Tensor, amplitude: Tensor, direction: Tensor | None = None) -> Tensor:
        """Joints ``(B, 12)`` of the legs' ``phase`` and ``amplitude`` ``(B, 4)``, stepping
        forward, or along ``direction`` ``(B, 4)`` (rad from forward: planar steps)."""
        s = torch.sin(phase)
        dx = -amplitude * torch.cos(phase)
        dz = torch.where(s > 0, self.clearance * s, self.penetration * s)
        signs = self.signs.to(phase.dtype)
        z = self.foot[1].to(phase.dtype) + dz
        if direction is None:
            haa = self.offset.to(phase.dtype)[0::3].expand_as(phase)
        else:  # the step in the ground plane; the abduction puts the lateral part
            if not self.planar:
                raise ValueError(f"{type(self).__name__} built without lateral offsets steps "
                                 "forward only: give it lateral= for planar steps")  # fmt: skip
            lateral = self.lateral.to(phase.dtype)
            dx, dy = dx * torch.cos(direction), dx * torch.sin(direction)
            y = lateral + dy
            z_leg = -torch.sqrt((y * y + z * z - lateral * lateral).clamp(min=1e-6))
            haa = torch.atan2(z, y) - torch.atan2(z_leg, lateral)
            haa = torch.atan2(torch.sin(haa), torch.cos(haa))  # within (-pi, pi]
            z = z_leg
        # the target in the front leg's frame (the hind legs' mirrored front to back)
        x = self.foot[0].to(phase.dtype) + signs * dx
        hfe, kfe = self.inverse_kinematics(x, z)
        joints = torch.stack([haa, signs * hfe, signs * kfe], dim=-1)  # (B, 4, 3)
        return joints.reshape(*phase.shape[:-1], 12)
