"""Checks every robot's Gymnasium envs make alike: actions that are real numbers, a render
mode the env offers, an episode of a bounded length."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

# control steps per episode at most: a typo (1e9) is refused rather than simulated for hours
from cpg_actor.limits import (
    MAX_DECIMATION,
    MAX_EPISODE_STEPS,
    MAX_RENDER_SIZE,
    MAX_SOLVER_ITERATIONS,
    brief,
    check_int,
    shorten,
)

# a simulation's counts every robot's config has, and their upper bounds
SIMULATION_COUNTS = (
    ("decimation", MAX_DECIMATION),
    ("mjx_iterations", MAX_SOLVER_ITERATIONS),
    ("mjx_ls_iterations", MAX_SOLVER_ITERATIONS),
    ("render_width", MAX_RENDER_SIZE),
    ("render_height", MAX_RENDER_SIZE),
)


def check_simulation_counts(config: Any) -> None:
    """ValueError (one line) for the first of :data:`SIMULATION_COUNTS` that is not an
    integer from 1 to its bound."""
    for name, high in SIMULATION_COUNTS:
        check_int(getattr(config, name), name, 1, high)


def real_actions(actions: Any, expected: str, dtype: Any = np.float64) -> np.ndarray:
    """``actions`` as a real ``dtype`` array; ValueError for what is not numbers, and for
    complex numbers (numpy would drop their imaginary part with only a warning)."""
    try:
        raw = np.asarray(actions)
        is_complex = np.iscomplexobj(raw)
        array = None if is_complex else raw.astype(dtype)
    except (TypeError, ValueError):
        raise ValueError(f"actions must be numbers {expected}, got {brief(actions)}") from None
    if is_complex:
        raise ValueError(
            f"actions must be real numbers {expected}, got complex values (dtype {raw.dtype})"
        )
    return array


def check_real_tensor(actions: Any) -> None:
    """ValueError for a complex tensor of actions (as :func:`real_actions`)."""
    if actions.is_complex():
        raise ValueError(f"actions must be real numbers, got complex values ({actions.dtype})")


def check_render_mode(render_mode: str | None, metadata: dict[str, Any]) -> None:
    """ValueError unless ``render_mode`` is None or one of ``metadata["render_modes"]``."""
    if render_mode is not None and render_mode not in metadata["render_modes"]:
        raise ValueError(
            f"render_mode must be None or one of {metadata['render_modes']}, "
            f"got {brief(render_mode)}"
        )


def check_episode_steps(steps: float, given: str) -> None:
    """ValueError unless an episode of ``steps`` control steps (from ``given``, the field and
    its value; a float where it is a quotient, which may be infinite) is at most
    :data:`MAX_EPISODE_STEPS`."""
    if not steps <= MAX_EPISODE_STEPS:
        steps = f"{steps:,.0f}" if steps < 1e12 else f"{steps:.3g}"  # (or infinite)
        raise ValueError(f"{given} makes episodes of {steps} control steps; at most "
                         f"{MAX_EPISODE_STEPS:,} are accepted")  # fmt: skip


def mapping_fields(cls: type, value: Any, label: str, sequences: tuple[str, ...] = ()) -> dict:
    """The fields of dataclass ``cls`` given as a mapping (a config file's ``label`` section);
    ValueError for what is not a mapping and for unknown keys, listing the valid ones. The
    fields named in ``sequences`` become tuples (YAML reads them as lists)."""
    if not isinstance(value, dict):
        raise ValueError(f"{label} must be a mapping of its fields, got {brief(value)}")
    names = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(str(k) for k in value if k not in names)
    if unknown:
        raise ValueError(f"unknown {label} key(s) {shorten(', '.join(unknown))}; accepted: "
                         f"{', '.join(names)}")  # fmt: skip
    values = dict(value)
    for name in sequences:
        if isinstance(values.get(name), list):
            values[name] = tuple(values[name])
    return values
