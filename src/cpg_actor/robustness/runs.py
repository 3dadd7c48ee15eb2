"""The runs the suite evaluates: run directories (``cpg-actor train``'s) and reproduction
directories (``cpg-actor reproduce``'s ``OUT/runs/VARIANT/seedS``, every run of them), each
with the variant it is grouped under and its seed."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

CHECKPOINT = Path("checkpoints") / "last.pt"  # a run's final policy


@dataclass(frozen=True)
class RunRef:
    variant: str  # what it is grouped under: the reproduction's variant, else the agent
    seed: int
    path: Path
    robot: str


def find_runs(paths: list[str | Path]) -> list[RunRef]:
    """Every run the arguments name, in their order: a run directory is one run (its variant
    its parent folder's name when it is a reproduction's ``seedS``, else its agent's), a
    reproduction directory (one with ``runs/``) is each of its runs that has a final
    checkpoint. FileNotFoundError for a path that is neither; ValueError for a run named
    twice (it would count as two seeds)."""
    from cpg_actor.config.saved import read_config, run_robot

    found: list[RunRef] = []
    for given in paths:
        path = Path(given)
        if (path / "runs").is_dir():
            runs = [run for run in reproduction_runs(path) if (run[2] / CHECKPOINT).is_file()]
            if not runs:
                raise FileNotFoundError(f"{path}: a reproduction directory without a finished "
                                        f"run ({CHECKPOINT} in runs/VARIANT/seedS)")  # fmt: skip
            for variant, seed, run_dir in runs:
                robot = run_robot(read_config(run_dir)).name
                found.append(RunRef(variant, seed, run_dir, robot))
            continue
        if not (path / "config.yaml").is_file():
            raise FileNotFoundError(f"{path} is neither a run directory (config.yaml) nor a "
                                    "reproduction directory (runs/)")  # fmt: skip
        if not (path / CHECKPOINT).is_file():
            raise FileNotFoundError(f"{path / CHECKPOINT} does not exist: the run has no "
                                    "final policy")  # fmt: skip
        config = read_config(path)
        seed_dir = re.fullmatch(r"seed(\d+)", path.name)
        if seed_dir:
            variant, seed = path.resolve().parent.name, int(seed_dir.group(1))
        else:
            variant, seed = str(config.get("agent", path.name)), int(config.get("seed", 0))
        found.append(RunRef(variant, seed, path, run_robot(config).name))
    seen: dict[Path, Path] = {}  # resolved -> as given
    for run in found:
        first = seen.get(run.path.resolve())
        if first is not None:
            twice = str(run.path) if run.path == first else f"{first} and {run.path}"
            raise ValueError(f"{twice}: the same run given twice; give each run once (a "
                             "reproduction directory gives every run in it)")  # fmt: skip
        seen[run.path.resolve()] = run.path
    robots = sorted({run.robot for run in found})
    if len(robots) > 1:
        raise ValueError(f"the runs are of several robots ({', '.join(robots)}), whose "
                         "perturbations differ: run the suite once per robot")  # fmt: skip
    return found


def reproduction_runs(out: Path) -> list[tuple[str, int, Path]]:
    """``(variant, seed, run directory)`` of every ``OUT/runs/VARIANT/seedS`` of a reproduction
    directory, by variant name then seed."""
    found = []
    for variant in sorted(p for p in (Path(out) / "runs").iterdir() if p.is_dir()):
        seeds = [(int(p.name[4:]), p) for p in variant.iterdir()
                 if p.is_dir() and re.fullmatch(r"seed\d+", p.name)]  # fmt: skip
        found += [(variant.name, seed, path) for seed, path in sorted(seeds)]
    return found
