"""The joint map: desired joint positions from CPG outputs, around a nominal pose."""

from __future__ import annotations

from collections.abc import Sequence

import torch
from torch import Tensor, nn


class JointMap(nn.Module):
    """Desired joint positions from CPG outputs: ``p_d = offset + x`` (one oscillator per joint),
    or ``p_d[joints[k]] = offset + x_k`` with ``joints`` naming the joint each oscillator
    drives, the other joints held at their offset (the quadruped's HAA joints).

    The offset is the nominal pose, fixed by default: the CPG then oscillates around a known
    standing posture and every trainable degree of freedom stays in the CPG (and its feedback).
    ``learnable_offset=True`` makes it a trainable parameter instead.
    """

    def __init__(
        self,
        offset: Sequence[float],
        learnable_offset: bool = False,
        joints: Sequence[int] | None = None,
    ) -> None:
        super().__init__()
        offset_tensor = torch.as_tensor(offset, dtype=torch.get_default_dtype())
        if learnable_offset:
            self.offset = nn.Parameter(offset_tensor)
        else:
            self.register_buffer("offset", offset_tensor)
        num_joints = offset_tensor.shape[0]
        joints = list(range(num_joints)) if joints is None else [int(j) for j in joints]
        if not all(0 <= j < num_joints for j in joints) or len(set(joints)) != len(joints):
            raise ValueError(
                f"joints must be distinct indices in 0..{num_joints - 1}, got {joints}"
            )
        self.identity = joints == list(range(num_joints))
        selection = torch.zeros(len(joints), num_joints, dtype=offset_tensor.dtype)
        selection[range(len(joints)), joints] = 1.0
        # (oscillators, joints), one 1 per row; rebuilt from the arguments, not checkpointed
        self.register_buffer("selection", selection, persistent=False)

    def forward(self, x: Tensor) -> Tensor:
        if x.shape[-1] != self.selection.shape[0]:
            raise ValueError(
                f"CPG output has {x.shape[-1]} oscillators, the joint map expects "
                f"{self.selection.shape[0]}"
            )
        if self.identity:
            return x + self.offset
        return x @ self.selection.to(x.dtype) + self.offset
