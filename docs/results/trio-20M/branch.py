"""Branch a run from one of its checkpoints with changed config values, for a diagnostic:
``cpg-actor train --resume`` refuses a changed config (a resumed run continues the same run),
so this writes a new run directory whose config and checkpoint carry the change.

    python docs/results/trio-20M/branch.py RUN ITERATION OUT KEY=VALUE [KEY=VALUE ...]
    cpg-actor train --resume --run-dir OUT --total-steps N

The CPG's Adam group keeps its rate in the checkpoint's optimizer state, so a changed
``ppo.cpg_learning_rate`` is written there too. Values are YAML: write 0.00003, not 3e-5
(YAML 1.1 reads that as a string).
"""

import shutil
import sys
from pathlib import Path

import torch
import yaml

from cpg_actor.safe_yaml import parse_yaml, read_yaml


def apply(config: dict, overrides: list[list[str]]) -> dict:
    for key, value in overrides:
        *path, last = key.split(".")
        node = config
        for part in path:
            node = node[part]
        node[last] = parse_yaml(value)
    return config


def main() -> None:
    source, iteration, out = Path(sys.argv[1]), int(sys.argv[2]), Path(sys.argv[3])
    overrides = [a.split("=", 1) for a in sys.argv[4:]]
    (out / "checkpoints").mkdir(parents=True)  # refuses an existing OUT
    shutil.copy(source / "metrics.jsonl", out / "metrics.jsonl")  # resume trims what follows
    shutil.copy(source / ".cpg-actor-run", out / ".cpg-actor-run")
    config = apply(read_yaml(source / "config.yaml"), overrides)
    (out / "config.yaml").write_text(yaml.safe_dump(config, sort_keys=False))
    checkpoint = torch.load(source / "checkpoints" / f"iter_{iteration:06d}.pt", weights_only=False)
    checkpoint["config"] = apply(checkpoint["config"], overrides)
    for group in checkpoint["optimizer"]["param_groups"]:
        if group.get("fixed_lr"):
            group["lr"] = checkpoint["config"]["ppo"]["cpg_learning_rate"]
    for name in (f"iter_{iteration:06d}.pt", "last.pt"):
        torch.save(checkpoint, out / "checkpoints" / name)
    print(f"branched {out} at {checkpoint['global_step']:,} steps")


if __name__ == "__main__":
    main()
