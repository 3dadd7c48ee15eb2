"""Drawing shared by the commands that write figures: the gait diagram (which foot is on the
ground, per leg, over time) of ``cpg-actor gaits`` and ``cpg-actor eval``, and an atomic
``savefig``."""

from __future__ import annotations

import os
import uuid
from collections.abc import Sequence
from pathlib import Path

import numpy as np

GAIT_WINDOW = 2.0  # s: the last seconds a gait diagram shows


def draw_gait_diagram(
    axis,
    contact: np.ndarray,
    dt: float,
    legs: Sequence[str],
    window: float = GAIT_WINDOW,
    first_time: float = 0.0,
) -> None:
    """Draw on the matplotlib ``axis`` the last ``window`` seconds of a ``(T, legs)`` contact
    trace (row k at time ``first_time + k dt``): a bar for every step a foot is on the ground,
    one row per leg, the first leg on top."""
    contact = np.asarray(contact, dtype=bool)
    n = len(legs)
    shown = contact[-max(1, round(window / dt)) :]
    start = first_time + (len(contact) - len(shown)) * dt
    for leg in range(n):
        on = np.flatnonzero(shown[:, leg])
        axis.broken_barh([(start + k * dt, dt) for k in on], (n - 1 - leg - 0.4, 0.8),
                         color="tab:blue")  # fmt: skip
    axis.set_yticks(range(n), list(legs)[::-1])
    axis.set_ylim(-0.6, n - 0.4)
    axis.set_xlim(start, start + len(shown) * dt)


def save_figure(fig, path: str | os.PathLike, dpi: int = 110) -> Path:
    """``fig.savefig`` to a hidden name next to ``path``, then renamed: an existing file is
    replaced whole or not at all."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp{path.suffix}")
    try:
        fig.savefig(tmp, dpi=dpi)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path
