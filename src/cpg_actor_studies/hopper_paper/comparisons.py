"""Questions beyond the paper's claims, each a pair of variants run together (is the first
better than the second?), judged on the final return and hop height as one family."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from cpg_actor.api import statistics as st

TOO_FEW = f"not tested (< {st.MIN_SEEDS} seeds)"

# Questions beyond the paper's claims, each a pair (first, second) of variants run together:
# is the first better than the second?
COMPARISONS = (
    ("cpg-actor-bptt32", "cpg-actor-paper", "32-step gradient vs the paper's one step"),
    ("cpg-actor-feedback-noise", "cpg-actor-paper", "feedback noise vs the paper's gradient"),
    ("cpg-actor-unbounded", "cpg-actor-paper", "the paper's unbounded feedback vs bounded"),
    ("mlp", "cpg-actor", "MLP vs CPG-Actor, eq. 4 reward"),
    ("mlp-apex", "cpg-actor-apex", "MLP vs CPG-Actor, apex (hop-height) reward"),
    ("cpg-actor", "cho2019-warm", "CPG-Actor vs Cho et al. from the same start gait"),
    ("cpg-actor", "cho2019-paper", "CPG-Actor vs Cho et al. as the paper has it"),
    ("cho2019-warm", "cho2019-paper", "the stronger Cho et al. vs the paper's"),
    ("cpg-actor", "cpg-actor-paper", "CPG-Actor vs the CPG-Actor in the paper's form"),
    ("cpg-actor", "open-loop-es", "the feedback vs the best open loop it starts from"),
    ("cpg-actor", "mlp-warm", "the CPG's structure vs the same start without it"),
    ("open-loop-es", "cpg-actor-open-loop", "open-loop CPG: black-box search vs PPO"),
    ("mlp-warm", "mlp", "MLP actor warm-started vs from scratch"),
)


# the metrics of the comparisons: (per-seed key, name in a row, key of st.MINIMUM_EFFECT)
COMPARED = (("final_return", "return", "return"), ("final_hop_height_logged", "hop", "hop_height"))


def judge_comparisons(
    seeds: dict[str, dict[str, list[float]]],
    pairs: Sequence[tuple[str, str, str]] = COMPARISONS,
) -> list[dict[str, Any]]:
    """For each pair of ``pairs`` (default :data:`COMPARISONS`; a stored report's own pairs
    when it is judged again) that ran: the differences of the final
    (logged, deterministic) return and hop height, with bootstrap CIs over seeds (shown), and
    which one is better: Welch's t-test, Holm-corrected over every test of the table (one
    family), the difference at least the metric's minimum effect (of the second's mean);
    neither with fewer than ``MIN_SEEDS`` seeds a side. Each row keeps ``NAME_p``: [p, Holm
    p] and the family's size."""
    rows, tests = [], []
    for first, second, question in pairs:
        if first not in seeds or second not in seeds:
            continue
        row: dict[str, Any] = {"first": first, "second": second, "question": question}
        for key, name, metric in COMPARED:
            a, b = seeds[first][key], seeds[second][key]
            if not st.enough_seeds(a, b):
                row[name], row[f"{name}_better"], row[f"{name}_p"] = None, TOO_FEW, None
                continue
            interval = st.bootstrap_difference(a, b)
            row[name] = [interval.estimate, interval.low, interval.high]
            difference, p = st.welch_test(a, b)
            minimum = st.MINIMUM_EFFECT[metric].threshold(float(np.mean(st.finite(b))))
            tests.append((row, name, difference, p, minimum))
        rows.append(row)
    adjusted = st.holm([p for *_, p, _ in tests])
    for (row, name, difference, p, minimum), holm_p in zip(tests, adjusted, strict=True):
        row[f"{name}_p"] = [p, holm_p]
        resolved = holm_p < st.ALPHA and abs(difference) >= minimum and difference != 0
        better = row["first"] if difference > 0 else row["second"]
        row[f"{name}_better"] = better if resolved else "not resolved"
    for row in rows:
        row["family"] = len(tests)
    return rows
