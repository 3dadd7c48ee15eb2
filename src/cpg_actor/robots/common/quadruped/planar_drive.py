"""The velocity command as each leg's drive and step direction (the ``leg`` layout's planar
steps, ``agent_config.cpg_planar_steps``): CPG-RL's foot-space pattern (Bellegarda and Ijspeert
2022) extended from forward steps to steps in the ground plane.

A base moving at the commanded planar velocity (v_x, v_y) and turning at the yaw rate w_z
carries the point of the base above foot i, at (x_i, y_i) in the base frame, at

    u_i = (v_x - w_z y_i,  v_y + w_z x_i)                  (v + w x p_i, base frame)

A stance foot stands still on the ground, so it moves against the base at -u_i: the foot's
step points along u_i, and its length grows with |u_i|. Each leg's oscillator is driven (eq. 3)
by

    d_i = |u_i|                (m/s: the step's length rho(d_i) and frequency nu(d_i))
    psi_i = atan2(u_i,y, u_i,x)  (the step's direction, rad from forward; 0 where d_i = 0)

so side steps and turning are in the prior: a yaw command steps the left and right feet in
opposite directions, a lateral one steps every foot sideways. For a forward command (v_y =
w_z = 0, v_x >= 0) d_i is v_x and psi_i is 0 for every leg: the forward drive exactly. The
legs' frequencies differ where their speeds do (turning while walking); the coupling holds
them in the gait, as it does against the feedback's xi.
"""

from __future__ import annotations

from collections.abc import Sequence

import torch
from torch import Tensor, nn

from cpg_actor.robots.common.quadruped.foot_space import Vec2


class PlanarDrive(nn.Module):
    """The command ``(B, 3)`` (forward, lateral m/s, yaw rate rad/s) -> each leg's drive
    ``d_i`` ``(B, 4)`` (m/s) and step direction ``psi_i`` ``(B, 4)`` (rad), by the module
    docstring.

    Args:
        feet: each foot's nominal place (x, y) in the base frame, m, in the legs' order.
    """

    def __init__(self, feet: Sequence[Vec2]) -> None:
        super().__init__()
        feet = torch.as_tensor(feet, dtype=torch.float64)
        if feet.shape != (4, 2):
            raise ValueError(f"{type(self).__name__} needs 4 feet (x, y), got {tuple(feet.shape)}")
        self.register_buffer("feet", feet, persistent=False)  # the robot's geometry

    def forward(self, command: Tensor) -> tuple[Tensor, Tensor]:
        feet = self.feet.to(command.dtype)
        vx, vy, yaw = command[:, 0:1], command[:, 1:2], command[:, 2:3]
        ux = vx - yaw * feet[:, 1]
        uy = vy + yaw * feet[:, 0]
        # sqrt(x^2) is |x| exactly in binary floating point: a forward command's drive is it
        drive = torch.sqrt(ux * ux + uy * uy)
        direction = torch.where(drive > 0, torch.atan2(uy, ux), torch.zeros_like(drive))
        return drive, direction
