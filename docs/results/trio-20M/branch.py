"""Branch a run from one of its checkpoints with changed config values, for a diagnostic:
``cpg-actor train --resume`` refuses a changed config (a resumed run continues the same run),
so this writes a new run directory whose config and checkpoint carry the change.

    python docs/results/trio-20M/branch.py RUN ITERATION OUT KEY=VALUE [KEY=VALUE ...]
    cpg-actor train --resume --run-dir OUT --total-steps N

The CPG's Adam group keeps its rate in the checkpoint's optimizer state, so a changed
``ppo.cpg_learning_rate`` is written there too. Values are read as ``cpg-actor train --set``
reads them (YAML; 3e-5 a number). The checkpoint is read as ``cpg-actor train --resume``
reads it (tensors and plain data only, never code); OUT must not exist yet.
"""

import shutil
import sys
from pathlib import Path

import yaml

from cpg_actor.api import load_checkpoint, parse_override, read_config_file
from cpg_actor.files import RUN, write_marker
from cpg_actor.training.checkpoint import atomic_save

USAGE = "usage: branch.py RUN ITERATION OUT KEY=VALUE [KEY=VALUE ...]"


def apply(config: dict, overrides: list[list[str]], where: str) -> dict:
    """``config`` with each ``KEY=VALUE`` set; ValueError for a key it does not have."""
    for key, text in overrides:
        *path, last = key.split(".")
        node = config
        for part in path:
            node = node.get(part) if isinstance(node, dict) else None
        if not isinstance(node, dict) or last not in node:
            raise ValueError(f"{key}: {where} has no such key")
        node[last] = parse_override(f"value={text}")["value"]
    return config


def branch(source: Path, iteration: int, out: Path, overrides: list[list[str]]) -> None:
    """Write OUT, the branch of ``source`` at ``iteration`` with ``overrides``; everything is
    read and checked before OUT is made, and OUT is removed again if writing it fails."""
    if out.exists():
        raise ValueError(f"{out} exists; give a new folder for the branch")
    for name in ("metrics.jsonl", "config.yaml"):
        if not (source / name).is_file():
            raise ValueError(f"{source} has no {name}: not a run directory of cpg-actor train")
    config = apply(read_config_file(source / "config.yaml"), overrides, f"{source}/config.yaml")
    checkpoint = load_checkpoint(source / "checkpoints" / f"iter_{iteration:06d}.pt")
    checkpoint["config"] = apply(checkpoint["config"], overrides, "its checkpoint's config")
    for group in checkpoint["optimizer"]["param_groups"]:
        if group.get("fixed_lr"):
            group["lr"] = checkpoint["config"]["ppo"]["cpg_learning_rate"]
    (out / "checkpoints").mkdir(parents=True)
    try:
        shutil.copy(source / "metrics.jsonl", out / "metrics.jsonl")  # resume trims the rest
        write_marker(out, RUN)
        (out / "config.yaml").write_text(yaml.safe_dump(config, sort_keys=False))
        for name in (f"iter_{iteration:06d}.pt", "last.pt"):
            atomic_save(checkpoint, out / "checkpoints" / name)
    except BaseException:
        shutil.rmtree(out)  # this script's own, half written
        raise
    print(f"branched {out} at {checkpoint['global_step']:,} steps")


def main(argv: list[str]) -> int:
    if len(argv) < 4 or not argv[1].isdigit() or any("=" not in a for a in argv[3:]):
        print(f"branch.py: error: {USAGE} (ITERATION a checkpoint's number)", file=sys.stderr)
        return 2
    overrides = [a.split("=", 1) for a in argv[3:]]
    try:
        branch(Path(argv[0]), int(argv[1]), Path(argv[2]), overrides)
    except (ValueError, OSError) as error:  # a missing, damaged or foreign file: one line
        print(f"branch.py: error: {error}", file=sys.stderr)
        return 2 if isinstance(error, ValueError) else 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
