"""Read a results directory: per run, the training curve, the stage evaluations, checkpoints."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from cpg_actor.metrics.signals import desired_velocity
from cpg_actor_studies.reproduction.execute import MARKER, STAGES_FILE, list_checkpoints

# What kind of agent a variant is, where the report tells them apart (the CPG figures, the
# Cho et al. claims); names not listed go by their prefix (:func:`agent_kind`)
KINDS = {
    "cpg-actor-paper": "cpg",
    "open-loop-es": "cpg",
    "mlp-warm": "mlp",
}


def agent_kind(variant: str) -> str | None:
    """``"cho"`` (the CPG in the environment, Cho et al.), ``"cpg"`` (a CPG in the agent:
    the CPG-Actor in any form, open-loop CPGs) or ``"mlp"``; None for a name of no known kind."""
    if variant in KINDS:
        return KINDS[variant]
    for prefix, kind in (("cho2019", "cho"), ("cpg-actor", "cpg"), ("open-loop", "cpg"),
                         ("mlp", "mlp")):  # fmt: skip
        if variant.startswith(prefix):
            return kind
    return None


def trace_control_dt(traces: dict[str, np.ndarray]) -> float | None:
    """The control period of a traces file: its ``control_dt``, else the step of its
    ``time`` (traces saved before ``control_dt`` was); None if neither says."""
    if "control_dt" in traces:
        return float(traces["control_dt"])
    time = np.asarray(traces.get("time", ()), dtype=float).ravel()
    return float(time[1] - time[0]) if time.size > 1 and time[1] > time[0] else None


def trace_joint_limits(traces: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray] | None:
    """The action space's bounds (rad, per joint) the traces' desired positions were clipped
    to: ``action_low`` / ``action_high`` as :func:`cpg_actor.training.evaluation.evaluate` saves
    them; for traces saved before it did, the joint limits of the robot the paper studies when
    the traces are its (the hopper's: joints HFE, KFE, or no joint names); None otherwise."""
    if "action_low" in traces and "action_high" in traces:
        return np.asarray(traces["action_low"], float), np.asarray(traces["action_high"], float)
    from cpg_actor.api import paper_robot

    names = traces.get("joint_names")
    joints = None if names is None else tuple(str(name) for name in names)
    return paper_robot().paper_parts().joint_limits(joints)


def sent_positions(traces: dict[str, np.ndarray]) -> np.ndarray | None:
    """The desired joint positions the env tracked, ``(T, E, joints)``; None where the traces
    hold no such array (one column per joint of ``joint_names``, the hopper's 2 for traces
    without names)."""
    position = traces.get("desired_position")
    joints = len(traces["joint_names"]) if "joint_names" in traces else 2
    if position is None or position.ndim != 3 or position.shape[-1] != joints:
        return None
    return np.asarray(position, dtype=float)


def sent_velocity(traces: dict[str, np.ndarray]) -> np.ndarray | None:
    """Every agent's desired velocity: the finite difference of :func:`sent_positions` over
    the control period (:func:`cpg_actor.metrics.signals.desired_velocity`; the first step
    of an episode NaN), computed here from the positions so that traces saved when CPG agents
    stored their analytic ``x_dot`` instead are read alike; None where it cannot be."""
    position, dt = sent_positions(traces), trace_control_dt(traces)
    return None if position is None or dt is None else desired_velocity(position, dt)


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
        from cpg_actor.api import read_config

        return read_config(self.path)

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
