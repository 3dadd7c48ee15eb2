"""Read a results directory: per run, the training curve, the stage evaluations, checkpoints."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from cpg_actor.experiments.execute import MARKER, STAGES_FILE, list_checkpoints

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
    "open-loop-es": "open-loop CPG (CMA-ES)",
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
    "open-loop-es": "tab:gray",
}


def label(variant: str) -> str:
    return LABELS.get(variant, variant)


def color(variant: str) -> str | None:
    return COLORS.get(variant)


@dataclass
class Run:
    variant: str
    seed: int
    path: Path

    @cached_property
    def metrics(self) -> list[dict[str, Any]]:
        path = self.path / "metrics.jsonl"
        if not path.is_file():
            return []
        rows = []
        for line in path.read_text().splitlines():
            try:
                rows.append(json.loads(line))
            except ValueError:
                continue  # a line cut short by an interrupted run
        return rows

    def curve(self, key: str) -> tuple[np.ndarray, np.ndarray]:
        rows = self.metrics
        steps = np.array([r.get("global_step", np.nan) for r in rows], dtype=float)
        values = np.array([np.nan if r.get(key) is None else r[key] for r in rows], dtype=float)
        return steps, values

    def return_curve(self) -> tuple[np.ndarray, np.ndarray]:
        """The deterministic evaluation's return during training (``eval/return``); the
        exploration return (``charts/episode_return``) for runs logged without evaluation."""
        steps, values = self.curve("eval/return")
        if np.isfinite(values).any():
            return steps, values
        return self.curve("charts/episode_return")

    @property
    def finished(self) -> bool:
        marker = self.path / MARKER
        try:
            return json.loads(marker.read_text()).get("status") == "done"
        except (OSError, ValueError):
            return False

    @property
    def commit(self) -> str:
        """The commit the run was trained at (its marker's record; older runs did not keep it)."""
        try:
            return json.loads((self.path / MARKER).read_text()).get("commit") or "not recorded"
        except (OSError, ValueError):
            return "not recorded"

    @cached_property
    def config(self) -> dict[str, Any]:
        """The run's saved ``config.yaml`` as a mapping (empty if it has none)."""
        import yaml

        try:
            return yaml.safe_load((self.path / "config.yaml").read_text()) or {}
        except (OSError, yaml.YAMLError):
            return {}

    @cached_property
    def stages(self) -> list[dict[str, Any]]:
        path = self.path / "eval" / STAGES_FILE
        try:
            return json.loads(path.read_text()) if path.is_file() else []
        except ValueError:
            return []

    def traces(self, stage: int = -1) -> dict[str, np.ndarray] | None:
        """The eval traces of a stage (default: the last, i.e. the end of training)."""
        stages = self.stages
        if not stages:
            return None
        path = self.path / stages[stage]["traces"]
        if not path.is_file():
            return None
        with np.load(path, allow_pickle=False) as data:
            return {key: data[key] for key in data.files}

    def checkpoints(self) -> dict[int, Path]:
        return list_checkpoints(self.path)


@dataclass
class Results:
    """All runs under ``OUT/runs/VARIANT/seedS`` (in the order of ``variants`` when given)."""

    out: Path
    variants: list[str]
    runs: dict[str, list[Run]] = field(default_factory=dict)

    @classmethod
    def load(cls, out: Path, variants: list[str] | None = None) -> Results:
        out = Path(out)
        root = out / "runs"
        found = sorted(p.name for p in root.iterdir() if p.is_dir()) if root.is_dir() else []
        order = list(variants) if variants else found
        runs: dict[str, list[Run]] = {}
        for variant in order:
            directory = root / variant
            if not directory.is_dir():
                continue
            seeds = []
            for path in directory.iterdir():
                if path.is_dir() and path.name.startswith("seed") and path.name[4:].isdigit():
                    seeds.append(Run(variant, int(path.name[4:]), path))
            seeds.sort(key=lambda run: run.seed)
            if seeds:
                runs[variant] = seeds
        return cls(out, order, runs)

    def has(self, variant: str) -> bool:
        return bool(self.runs.get(variant))

    def first(self, variant: str) -> Run | None:
        """The lowest-seed run of a variant (seed 0 normally), for the trace figures."""
        runs = self.runs.get(variant) or []
        return runs[0] if runs else None
