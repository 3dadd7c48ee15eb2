"""Checkpoint files: atomic writes, loading with clear errors, the file a resume starts
from, RNG streams, and the config keys that differ between two runs."""

from __future__ import annotations

import os
import random
from pathlib import Path
from typing import Any

import numpy as np
import torch

CHECKPOINT_FORMAT = "cpg-actor-checkpoint"
CHECKPOINT_VERSION = 1


def rng_state() -> dict[str, Any]:
    kind, keys, pos, has_gauss, cached = np.random.get_state()  # noqa: NPY002
    return {
        "torch": torch.get_rng_state(),
        "numpy": [kind, torch.from_numpy(keys.astype(np.int64)), pos, has_gauss, cached],
        "python": random.getstate(),
        # CUDA's generators (action noise sampled on a GPU), where CUDA has been used
        **({"cuda": torch.cuda.get_rng_state_all()} if torch.cuda.is_initialized() else {}),
    }


def set_rng_state(state: dict[str, Any]) -> None:
    torch.set_rng_state(state["torch"])
    kind, keys, pos, has_gauss, cached = state["numpy"]
    np.random.set_state((kind, keys.numpy().astype(np.uint32), pos, has_gauss, cached))  # noqa: NPY002
    random.setstate(state["python"])
    if "cuda" in state and torch.cuda.is_available():
        torch.cuda.set_rng_state_all(state["cuda"])


def atomic_save(obj: Any, path: Path) -> None:
    """``torch.save`` to a temporary file in the same directory, fsync, then ``os.replace``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        with open(tmp, "wb") as f:
            torch.save(obj, f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def atomic_write_text(text: str, path: Path) -> None:
    """Write ``text`` to a temporary file in the same directory, then ``os.replace``."""
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        tmp.write_text(text)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def load_checkpoint(path: Path) -> dict[str, Any]:
    """Load and sanity-check a checkpoint; a clear ValueError if it is not one of ours."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"checkpoint {path} does not exist")
    try:
        data = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as error:  # truncated, corrupt, or not a torch file at all
        raise ValueError(
            f"checkpoint {path} is corrupt or not a cpg-actor checkpoint "
            f"({error.__class__.__name__})"
        ) from None
    if not isinstance(data, dict) or data.get("format") != CHECKPOINT_FORMAT:
        raise ValueError(f"{path} is not a cpg-actor checkpoint")
    if data.get("version") != CHECKPOINT_VERSION:
        raise ValueError(
            f"checkpoint {path} has version {data.get('version')}, expected {CHECKPOINT_VERSION}"
        )
    return data


def check_checkpoint_run(
    path: Path, data: dict[str, Any], agent: str, robot: str | None = None
) -> None:
    """ValueError unless checkpoint ``data`` (read from ``path``) was trained with ``agent``
    (and on ``robot``, where given): a checkpoint of another run. Resume, ``cpg-actor eval``
    and ``cpg-actor export`` check the run's checkpoint with it."""
    if data["agent"] != agent:
        raise ValueError(
            f"checkpoint {path} was trained with agent '{data['agent']}', this run uses '{agent}'"
        )
    trained_on = data.get("config", {}).get("robot", "hopper")
    if robot is not None and trained_on != robot:
        raise ValueError(
            f"checkpoint {path} was trained on robot '{trained_on}', this run uses '{robot}'"
        )


def resume_checkpoint(run_dir: Path) -> tuple[Path, dict[str, Any], list[str]]:
    """The checkpoint a run resumes from: ``last.pt`` or, if it is missing or unreadable, the
    newest readable ``iter_*.pt`` (``last.pt`` is a copy of the newest one, so nothing is lost
    when that one is readable). Returns ``(path, data, notes)``, the notes saying what was
    skipped; FileNotFoundError / ValueError naming every file tried if none is usable."""
    folder = Path(run_dir) / "checkpoints"
    candidates = [folder / "last.pt", *sorted(folder.glob("iter_*.pt"), reverse=True)]
    candidates = [path for path in candidates if path.is_file()]
    if not candidates:
        raise FileNotFoundError(
            f"{folder} holds no checkpoint (last.pt, iter_*.pt); nothing to resume"
        )
    notes: list[str] = []
    for path in candidates:
        try:
            return path, load_checkpoint(path), notes
        except ValueError as error:
            notes.append(f"skipped {path.name}: {error}")
    raise ValueError(
        f"no usable checkpoint in {folder}: " + "; ".join(notes) + ". Start a new run."
    )


def config_differences(a: dict[str, Any], b: dict[str, Any], prefix: str = "") -> list[str]:
    """Dotted keys whose values differ between two nested config mappings."""
    keys = sorted(set(a) | set(b))
    out: list[str] = []
    for key in keys:
        x, y = a.get(key), b.get(key)
        if isinstance(x, dict) and isinstance(y, dict):
            out += config_differences(x, y, f"{prefix}{key}.")
        elif x != y:
            out.append(f"{prefix}{key}")
    return out
