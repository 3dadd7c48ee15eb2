"""The robustness suite's files (``cpg-actor robustness``; :mod:`cpg_actor.robustness`) and
their section in a reproduction's report: the suite run on a reproduction writes into
``OUT/robustness/``, and the report shows its verdicts."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from cpg_actor.experiments import metrics as m

JSON_FILE = "robustness.json"
MARKDOWN_FILE = "robustness.md"
REPORT_FOLDER = "robustness"  # a reproduction's suite, OUT/robustness/, goes into its report


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


def report_lines(out: Path) -> list[str]:
    """The reproduction report's robustness section, from ``OUT/robustness/robustness.json``
    (``cpg-actor robustness OUT --out OUT/robustness``); none without it."""
    path = Path(out) / REPORT_FOLDER / JSON_FILE
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return []
    return ["## Robustness", "",
            f"Per perturbation, the return retained under it (mean over its levels, per seed; "
            f"`{REPORT_FOLDER}/{MARKDOWN_FILE}` has every level), {data['episodes']} episodes "
            "per level.", "", *verdict_rule(data), *verdict_lines(data), ""]  # fmt: skip
