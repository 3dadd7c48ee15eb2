"""Checkpoint files: atomic writes, loading with clear errors, the file a resume starts
from, RNG streams, and the config keys that differ between two runs."""

from __future__ import annotations

import random
from pathlib import Path
from typing import Any

import numpy as np
import torch

from cpg_actor.files import atomic_write, atomic_write_text  # noqa: F401 (re-exported)

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
    """``torch.save`` to a temporary file in the same directory, fsync, then ``os.replace``
    (see :func:`cpg_actor.files.atomic_write`)."""
    atomic_write(Path(path), lambda f: torch.save(obj, f), fsync=True)


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
    """The checkpoint a run resumes from: the readable one of the highest iteration (stored in
    it), ``last.pt`` or an ``iter_*.pt``. ``last.pt`` is written after the ``iter_*.pt`` of the
    same iteration, so a run killed between the two has a newer ``iter_*.pt``; an unreadable
    file is skipped for the next. Returns ``(path, data, notes)``, the notes saying what was
    skipped; FileNotFoundError / ValueError naming every file tried if none is usable."""
    folder = Path(run_dir) / "checkpoints"
    numbered = sorted(
        (int(path.stem[len("iter_") :]), path)
        for path in folder.glob("iter_*.pt")
        if path.stem[len("iter_") :].isdigit() and path.is_file()
    )
    last = folder / "last.pt"
    if not numbered and not last.is_file():
        raise FileNotFoundError(
            f"{folder} holds no checkpoint (last.pt, iter_*.pt); nothing to resume"
        )
    notes: list[str] = []
    best: tuple[Path, dict[str, Any]] | None = None
    if last.is_file():
        try:
            best = last, load_checkpoint(last)
        except ValueError as error:
            notes.append(f"skipped {last.name}: {error}")
    newest = best[1].get("iteration", -1) if best else -1
    for number, path in reversed(numbered):  # the newest first; only those newer than last.pt
        if number <= newest:
            break
        try:
            data = load_checkpoint(path)
        except ValueError as error:
            notes.append(f"skipped {path.name}: {error}")
            continue
        if data.get("iteration", -1) > newest:
            return path, data, notes
    if best is not None:
        return best[0], best[1], notes
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
