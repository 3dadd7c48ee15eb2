"""A trained policy as one self-contained file for a robot's control loop: TorchScript or ONNX.

The exported function is the deterministic control step of :class:`cpg_actor.policy.Policy`:

    (observation, state) -> (action, next_state)

* ``observation``: ``(B, obs_dim)`` float32, the env's raw observation (for the hopper, in the
  order of ``cpg_actor.envs.OBS_NAMES``: measured HFE, KFE positions (rad) and velocities
  (rad/s), the desired positions being tracked (rad), hip height (m), hip velocity (m/s));
  the observation normaliser is inside.
* ``state``: ``(B, *state_shape)`` float32, the agent's recurrent state: for the CPG-Actor the
  CPG state ``(B, 5, N)`` (rows: phase theta, theta_dot, amplitude r, r_dot, r_ddot; columns:
  oscillators; on a robot with a drive, the quadruped, a sixth row: the drive d, set from the
  observation inside the step), for the MLP an empty ``(B, 0)``. Start from
  :func:`initial_state` (saved next to the policy as ``*.initial_state.npy``) and feed
  ``next_state`` back at the next step; restart it when an episode restarts.
* ``action``: ``(B, A)`` float32, desired joint positions (rad), the mean of the Gaussian,
  clipped to the joint limits.

The feedback network, the CPG step (eq. 1-2) and the joint map are inside; the batch size is
fixed at export (``batch``, default 1: one robot).
"""

from __future__ import annotations

import copy
import logging
import os
from pathlib import Path

import numpy as np
import torch
from torch import Tensor, nn

from cpg_actor.files import naming, temporary_path
from cpg_actor.policy import Policy

FORMATS = ("torchscript", "onnx")
SUFFIXES = {"torchscript": ".pt", "onnx": ".onnx"}
INPUT_NAMES = ["observation", "state"]
OUTPUT_NAMES = ["action", "next_state"]
EXPORTABLE = (
    "mlp",
    "mlp-warm",
    "cpg-actor",
    "cpg-actor-paper",
    "cpg-actor-open-loop",
    "open-loop-es",
)


class ControlStep(nn.Module):
    """``(observation, state) -> (action, next_state)``: normalise, act (mean), clip."""

    def __init__(self, policy: Policy) -> None:
        super().__init__()
        # a frozen copy: the exported step needs no gradients (outputs without requires_grad)
        self.agent = copy.deepcopy(policy.agent).requires_grad_(False)
        normalizer = policy.normalizer
        self.normalize = policy.normalize_observations
        self.register_buffer("mean", normalizer.mean.to(torch.float32))
        self.register_buffer("std", torch.sqrt(normalizer.var + normalizer.epsilon).float())
        self.clip = float(normalizer.clip)
        self.register_buffer("low", torch.as_tensor(policy.action_low, dtype=torch.float32))
        self.register_buffer("high", torch.as_tensor(policy.action_high, dtype=torch.float32))

    def forward(self, observation: Tensor, state: Tensor) -> tuple[Tensor, Tensor]:
        state = self.agent.observe(observation, state)  # e.g. the CPG's drive (raw obs)
        if self.normalize:
            observation = ((observation - self.mean) / self.std).clamp(-self.clip, self.clip)
        out = self.agent.actor(observation, state)
        action = torch.minimum(torch.maximum(out.mean, self.low), self.high)
        return action, out.next_state


def initial_state(policy: Policy, batch: int = 1) -> np.ndarray:
    """The recurrent state an episode starts from, ``(batch, *state_shape)`` float32."""
    return policy.agent.initial_state(batch).cpu().numpy().astype(np.float32)


def export_policy(
    policy: Policy, path: str | os.PathLike, fmt: str, batch: int = 1, overwrite: bool = False
) -> Path:
    """Write ``policy``'s control step to ``path`` in ``fmt`` (torchscript | onnx), and the
    initial state next to it (``PATH.initial_state.npy``). Atomic; refuses to replace an
    existing file unless ``overwrite``. Returns the path."""
    if fmt not in FORMATS:
        raise ValueError(f"unknown export format {fmt!r}; accepted: {', '.join(FORMATS)}")
    agent_name = getattr(policy.config, "agent", None)
    if agent_name is not None and agent_name not in EXPORTABLE:
        raise ValueError(
            f"agent '{agent_name}' acts on CPG parameters of a CPG inside its environment; "
            f"only agents that output joint positions can be exported: {', '.join(EXPORTABLE)}"
        )
    if isinstance(batch, bool) or not isinstance(batch, int) or batch < 1:
        raise ValueError(f"batch must be a positive integer, got {batch!r}")
    path = Path(path)
    state_path = path.with_name(path.name + ".initial_state.npy")
    for target in (path, state_path):
        if target.is_dir():  # not replaced even with --overwrite: a directory is no export
            raise FileExistsError(
                f"{target} is a directory; give the export a file name (e.g. "
                f"{target / ('policy' + SUFFIXES[fmt])})"
            )
        if target.exists() and not overwrite:
            raise FileExistsError(f"{target} exists; pass --overwrite to replace it")
    state_existed = state_path.exists()
    module = ControlStep(policy).cpu().eval()  # exported for the CPU, wherever it trained
    obs_dim = int(policy.normalizer.mean.shape[0])
    example = (torch.zeros(batch, obs_dim), torch.as_tensor(initial_state(policy, batch)))
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = temporary_path(path)
    state_tmp = temporary_path(state_path)
    try:
        with torch.no_grad(), naming(path):
            if fmt == "torchscript":
                torch.jit.save(torch.jit.trace(module, example), str(tmp))
            else:
                # the exporter logs a warning per torchvision operator it cannot register
                logging.getLogger("torch.onnx").setLevel(logging.ERROR)
                program = torch.onnx.export(
                    module,
                    example,
                    input_names=INPUT_NAMES,
                    output_names=OUTPUT_NAMES,
                    dynamo=True,
                    verbose=False,
                )
                program.save(str(tmp))
        with naming(state_path), open(state_tmp, "wb") as f:
            np.save(f, initial_state(policy, batch))
        os.replace(state_tmp, state_path)
        try:
            os.replace(tmp, path)
        except BaseException:  # no initial state left behind without its policy
            if not state_existed:
                state_path.unlink(missing_ok=True)
            raise
    finally:
        tmp.unlink(missing_ok=True)
        state_tmp.unlink(missing_ok=True)
    return path
