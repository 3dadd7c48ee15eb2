"""Where the networks, the rollout storage, the normalisers and the PPO update run.

``--device cpu`` (the default), ``cuda``, ``cuda:N`` or ``auto`` (CUDA if torch sees a GPU,
else the CPU). The simulators step on the CPU either way; observations go to the device and
actions come back once per control step.
"""

from __future__ import annotations

import re

import torch

from cpg_actor.limits import brief

DEVICE_PATTERN = re.compile(r"^(auto|cpu|cuda(:\d+)?)$")


def check_device_name(name: str) -> None:
    """ValueError unless ``name`` is cpu, cuda, cuda:N or auto."""
    if not isinstance(name, str) or not DEVICE_PATTERN.match(name):
        raise ValueError(f"device must be cpu, cuda, cuda:N or auto, got {brief(name)}")


def resolve_device(name: str) -> torch.device:
    """The torch device for ``name``; a clear ValueError if CUDA is asked for and absent."""
    check_device_name(name)
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    device = torch.device(name)
    if device.type == "cuda":
        if not torch.cuda.is_available():
            raise ValueError(
                f"device {brief(name)}: torch sees no CUDA device here (torch {torch.__version__}, "
                f"CUDA build {torch.version.cuda or 'none'}); use --device cpu or auto (a "
                f"resumed run keeps the device of its config.yaml: start a new run to change it)"
            )
        if device.index is not None and device.index >= torch.cuda.device_count():
            raise ValueError(
                f"device {brief(name)}: there are {torch.cuda.device_count()} CUDA device(s)"
            )
    return device
