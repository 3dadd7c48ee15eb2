"""The matched-smoothness strengths from the tuning runs' ``summary.json``: the per-seed table
and the rule of the README (strength 1: the alpha whose median command smoothness over the
seeds is closest in log to the CPG-Actor's; strength 2: the one closest in log to the
geometric mean of the CPG-Actor's and the unfiltered ``mlp-warm``'s).

    python choose.py REF_OUT A1=OUT1 A2=OUT2 ...

``REF_OUT`` holds ``cpg-actor`` and ``mlp-warm`` with no filter; each ``A=OUT`` holds
``mlp-warm`` with ``env.command_filter=A``. Prints markdown."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np

COLUMNS = (  # summary.json's per-seed key, header, format
    ("final_return", "final return", "{:.0f}"),
    ("hop_apex", "hop apex (m)", "{:.3f}"),
    ("joint_smoothness", "joint smoothness (rad^2)", "{:.3g}"),
    ("smoothness", "command smoothness (rad^2)", "{:.3g}"),
    ("torque_rate", "torque rate", "{:.3g}"),
)


def per_seed(out: Path, variant: str) -> dict[int, dict[str, float]]:
    """seed -> key -> value of ``variant``'s runs in ``out`` (seeds from the run folders,
    in the order the report lists them)."""
    summary = json.loads((out / "summary.json").read_text())
    values = summary["variants"][variant]["per_seed"]
    seeds = sorted(int(p.name[4:]) for p in (out / "runs" / variant).glob("seed*"))
    return {
        seed: {key: float(values[key][i]) for key, _, _ in COLUMNS} for i, seed in enumerate(seeds)
    }


def log_median(rows: dict[int, dict[str, float]], seeds: list[int]) -> float:
    """The median over ``seeds`` of the log command smoothness."""
    return float(np.median([math.log(rows[seed]["smoothness"]) for seed in seeds]))


def main(argv: list[str]) -> None:
    ref = Path(argv[0])
    rows = {
        "cpg-actor": per_seed(ref, "cpg-actor"),
        "mlp-warm (no filter)": per_seed(ref, "mlp-warm"),
    }
    alphas = {}
    for item in argv[1:]:
        alpha, out = item.split("=", 1)
        alphas[f"mlp-warm, alpha {alpha}"] = float(alpha)
        rows[f"mlp-warm, alpha {alpha}"] = per_seed(Path(out), "mlp-warm")
    seeds = sorted(set.intersection(*(set(r) for r in rows.values())))
    print("| variant | seed | " + " | ".join(h for _, h, _ in COLUMNS) + " |")
    print("| --- | ---: |" + " ---: |" * len(COLUMNS))
    for name, by_seed in rows.items():
        for seed in sorted(by_seed):
            cells = [fmt.format(by_seed[seed][key]) for key, _, fmt in COLUMNS]
            print(f"| {name} | {seed} | " + " | ".join(cells) + " |")
    cpg, mlp = log_median(rows["cpg-actor"], seeds), log_median(rows["mlp-warm (no filter)"], seeds)
    targets = {
        "strength 1 (the CPG-Actor's)": cpg,
        "strength 2 (the geometric mean)": (cpg + mlp) / 2,
    }
    print(
        f"\nseeds in common: {seeds}; median command smoothness: cpg-actor {math.exp(cpg):.3g}, "
        f"mlp-warm {math.exp(mlp):.3g}, their geometric mean {math.exp((cpg + mlp) / 2):.3g}"
    )
    for name in alphas:
        print(f"- {name}: median {math.exp(log_median(rows[name], seeds)):.3g}")
    for label, target in targets.items():
        best = min(alphas, key=lambda name: abs(log_median(rows[name], seeds) - target))
        print(
            f"- {label}: alpha {alphas[best]} (|log ratio| "
            f"{abs(log_median(rows[best], seeds) - target):.2f})"
        )


if __name__ == "__main__":
    main(sys.argv[1:])
