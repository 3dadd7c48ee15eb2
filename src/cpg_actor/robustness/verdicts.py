"""The robustness suite's claims (``cpg-actor robustness``; :mod:`cpg_actor.robustness`): one
variant more robust than another under a perturbation (:func:`verdict_more_robust`), judged with
the rest of the suite's claims as one family, and how its files state the verdicts."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from cpg_actor import statistics as m

JSON_FILE = "robustness.json"
MARKDOWN_FILE = "robustness.md"


def verdict_rule(data: dict[str, Any]) -> list[str]:
    """How the suite's verdicts are judged: the test, the family and the correction (none for
    verdicts of a file that does not record its family: each explanation says its rule)."""
    families = [row["family"] for row in data.get("verdicts") or [] if "family" in row]
    if not families:
        return []
    family = max(families)
    return [f"Per perturbation, per seed the mean over its levels of the return retained. A "
            f"claim is supported if the mean over seeds is higher by {m.WELCH} (two-sided), "
            f"with the {m.family_text(family)} (every claim and perturbation of this suite), "
            f"and the difference is at least {m.MINIMUM_EFFECT['retention']} (the minimum "
            f"effect of retention); not tested with fewer than {m.MIN_SEEDS} seeds a side. "
            "The bootstrap 95% CI of the difference is shown.", ""]  # fmt: skip


def verdict_lines(data: dict[str, Any]) -> list[str]:
    """The verdicts as a Markdown table (none: no lines)."""
    rows = data.get("verdicts") or []
    if not rows:
        return []
    lines = ["| claim | perturbation | verdict | why |", "| --- | --- | --- | --- |"]
    lines += [f"| {r['claim']} | {r['perturbation']} | **{r['verdict']}** | {r['why']} |"
              for r in rows]  # fmt: skip
    return lines


def verdict_more_robust(
    first: Sequence[float] | None,
    second: Sequence[float] | None,
    names: tuple[str, str] = ("cpg-actor", "mlp"),
) -> m.Claim:
    """ "``names[0]`` is more robust than ``names[1]``" under one perturbation: per seed, the
    return retained under it (:mod:`cpg_actor.robustness`; the mean over its levels of the
    return / the nominal return); supported if its mean over seeds is higher by Welch's t-test
    (the two are independent runs) and by the minimum effect of retention."""
    missing = m.too_few_seeds({names[0]: first, names[1]: second})
    if missing:
        return missing
    return m.Claim(
        f"mean retention over the levels {np.mean(m.finite(first)):.3g} ({names[0]}) vs "
        f"{np.mean(m.finite(second)):.3g} ({names[1]}), difference of means "
        f"{m.bootstrap_difference(first, second)}",
        [m.better_test(first, second, "retention", f"{names[0]} - {names[1]}")],
    )
