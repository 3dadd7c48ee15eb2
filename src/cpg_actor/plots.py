"""Drawing shared by the commands that write figures: the gait diagram (which foot is on the
ground, per leg, over time) of ``cpg-actor gaits`` and ``cpg-actor eval``, how an env's episode
metrics are named on an axis, the unit of a steps axis, step counts as legend labels, the
motor's velocity limit on a velocity axis, an agent's (or a study's variant's) name and colour
in a legend, and an atomic ``savefig``."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from cpg_actor.robots.registry import all_metrics

GAIT_WINDOW = 2.0  # s: the last seconds a gait diagram shows
# an agent's (or a variant's) name in a legend, and its colour
LABELS = {
    "cpg-actor": "CPG-Actor",
    "cpg-actor-open-loop": "CPG-Actor (open loop)",
    "cpg-actor-unbounded": "CPG-Actor (unbounded feedback)",
    "cho2019-warm": "Cho et al. (warm)",
    "cho2019": "Cho et al.",
    "cho2019-paper": "Cho et al. (paper's, warm)",
    "mlp": "MLP actor",
    "cpg-actor-apex": "CPG-Actor (apex reward)",
    "mlp-apex": "MLP actor (apex reward)",
    "cpg-actor-bptt32": "CPG-Actor (32-step gradient)",
    "cpg-actor-feedback-noise": "CPG-Actor (feedback noise)",
    "cpg-actor-paper": "CPG-Actor (paper's form)",
    "open-loop-es": "open-loop CPG (CMA-ES)",
    "mlp-warm": "MLP actor (warm)",
}
# the paper's colours: CPG-Actor green, open loop orange, Cho et al. warm red, cold blue
COLORS = {
    "cpg-actor": "tab:green",
    "cpg-actor-open-loop": "tab:orange",
    "cpg-actor-unbounded": "tab:olive",
    "cho2019-warm": "tab:red",
    "cho2019": "tab:blue",
    "cho2019-paper": "tab:pink",
    "mlp": "tab:purple",
    "cpg-actor-apex": "darkgreen",
    "mlp-apex": "indigo",
    "cpg-actor-bptt32": "tab:cyan",
    "cpg-actor-feedback-noise": "tab:brown",
    "cpg-actor-paper": "limegreen",
    "open-loop-es": "goldenrod",
    "mlp-warm": "mediumpurple",
}


def label(variant: str) -> str:
    return LABELS.get(variant, variant)


def color(variant: str) -> str | None:
    return COLORS.get(variant)


def metric_label(name: str) -> str:
    """An axis label for an episode metric: ``"hop height (m)"``; its name for one no robot
    describes (:func:`cpg_actor.robots.registry.all_metrics`)."""
    info = all_metrics().get(name)
    if info is None:
        return name.replace("_", " ")
    return f"{info.label} ({info.unit})" if info.unit else info.label


def step_labels(steps: Sequence[float]) -> list[str]:
    """Training step counts as short labels (``"4.1k"``, ``"20M"``), the unit chosen by the
    largest (k under a million, M from it), with as many digits as it takes for different
    counts to read differently."""
    values = [float(s) for s in steps]
    largest = max((abs(v) for v in values), default=0.0)
    scale, unit = (1e6, "M") if largest >= 1e6 else (1e3, "k") if largest >= 1e3 else (1.0, "")
    for digits in range(3, 10):
        labels = [f"{v / scale:.{digits}g}{unit}" if v else "0" for v in values]
        if len(set(labels)) == len(set(values)):
            return labels
    return [f"{v:,.0f}" for v in values]


def draw_velocity_limits(axis, limit: float | None) -> None:
    """Dashed lines at +-``limit`` (rad/s, the motor's speed limit) on a joint-velocity axis,
    labelled once for the legend; nothing where the limit is not known."""
    if limit is None or not np.isfinite(limit):
        return
    for sign in (1, -1):
        axis.axhline(sign * limit, color="tab:red", lw=1.0, ls="--",
                     label=f"motor speed limit ±{limit:g} rad/s" if sign > 0 else None)  # fmt: skip


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
    """A step count as budgets are written: ``"500k"``, ``"20M"``, ``"8.19k"``, ``"512"``."""
    return step_labels([steps])[0]


def save_figure(fig, path: str | os.PathLike, dpi: int | None = 110) -> Path:
    """``fig.savefig`` atomically (:func:`cpg_actor.files.atomic_write`): an existing file is
    replaced whole or not at all. The format is the suffix's."""
    from cpg_actor.files import atomic_write

    path = Path(path)
    fmt = path.suffix.removeprefix(".").lower() or None
    atomic_write(path, lambda f: fig.savefig(f, format=fmt, dpi=dpi))
    return path
