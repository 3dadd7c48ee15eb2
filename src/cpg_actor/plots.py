"""Drawing shared by the commands that write figures: the gait diagram (which foot is on the
ground, per leg, over time) of ``cpg-actor gaits`` and ``cpg-actor eval``, the unit of a
steps axis, and an atomic ``savefig``."""

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


def step_axis(largest: float, name: str = "training steps") -> tuple[float, str]:
    """``(divisor, label)`` of a steps axis reaching ``largest`` steps: millions from 1M on,
    thousands from 1k on, else plain steps (a 30k-step run reads 0-30, not 0.00-0.03)."""
    for divisor, unit in ((1e6, "millions"), (1e3, "thousands")):
        if largest >= divisor:
            return divisor, f"{name} ({unit})"
    return 1.0, name


def steps_text(steps: float) -> str:
    """A step count as budgets are written: ``"500k"``, ``"20M"``, ``"8.19k"`` (3 significant
    digits unless whole), ``"512"``."""
    for divisor, suffix in ((1e6, "M"), (1e3, "k")):
        if steps >= divisor:
            return f"{steps / divisor:.3g}{suffix}"
    return f"{steps:.0f}"


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
