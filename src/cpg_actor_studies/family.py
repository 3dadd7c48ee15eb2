"""A results folder's family of tests, as its ``PROTOCOL.md`` fixes it: per metric the variant
with the best mean against each other variant, every test Holm-corrected with the others, a
difference counted only when it also reaches its minimum effect. The analysis scripts of
``docs/results/`` share it; each test is a plain dict, so that they store it as JSON.

A test dict holds ``group`` (what is compared, e.g. the metric), ``label``, ``test`` (its
name), ``difference`` (oriented so that > 0 favours the claimed side; a log-ratio when ``log``),
``p``, ``minimum`` (on the difference's scale); :func:`judge` adds ``adjusted`` (Holm p),
``passed``, ``reversed`` and ``verdict`` ("yes", "reversed" or "no").
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from cpg_actor.api import statistics as st

VERDICTS = ("yes", "reversed", "no")


def judge(tests: list[dict[str, Any]], alpha: float = st.ALPHA) -> list[dict[str, Any]]:
    """Holm over ``tests`` (one family): a test counts ("yes") when its adjusted p < ``alpha``
    and its difference is at least its minimum (and above 0); "reversed" when the other side
    leads by at least the minimum with adjusted p < ``alpha`` (the tests are two-sided);
    else "no". Returns ``tests``, each updated in place."""
    for test, adjusted in zip(tests, st.holm([t["p"] for t in tests]), strict=True):
        significant = adjusted < alpha
        test["adjusted"] = adjusted
        test["passed"] = bool(
            significant and test["difference"] > 0 and test["difference"] >= test["minimum"]
        )
        test["reversed"] = bool(significant and -test["difference"] >= test["minimum"])
        test["verdict"] = "yes" if test["passed"] else "reversed" if test["reversed"] else "no"
    return tests


def mean_ci(values: Sequence[float], log: bool = False) -> st.Interval | None:
    """The mean over seeds with its percentile-bootstrap CI (display only); on a log scale the
    geometric mean, the interval taken on the logarithms and mapped back."""
    ci = st.bootstrap(np.log(np.asarray(values, dtype=float)) if log else values, "mean")
    if log and ci is not None:
        ci = st.Interval(*(math.exp(x) for x in (ci.estimate, ci.low, ci.high)))
    return ci


def shown(value: float, log: bool) -> str:
    """A difference as the tables print it: a factor on a log scale, else signed."""
    return f"x{math.exp(value):.3g}" if log else f"{value:+.3g}"


def best_against_others(
    data: Mapping[str, Sequence[float]],
    group: str,
    higher: bool,
    log: bool,
    minimum: Callable[[Sequence[float]], float],
) -> tuple[str, list[dict[str, Any]]]:
    """The variant with the best mean of ``data`` (variant: per-seed values; on the log
    scale when ``log``) and Welch's t-test of it against each other variant, oriented so that
    > 0 favours the best; ``minimum(other's values)`` is the smallest difference that counts.
    Not yet judged: :func:`judge` takes the whole family."""
    if len(data) < 2:
        raise ValueError(f"{group}: a comparison needs 2 or more variants, got {list(data)}")
    scaled = {v: np.log(np.asarray(x, dtype=float)) if log else np.asarray(x, dtype=float)
              for v, x in data.items()}  # fmt: skip
    sign = 1.0 if higher else -1.0
    best = max(scaled, key=lambda v: sign * float(np.nanmean(scaled[v])))
    tests = []
    for other in scaled:
        if other == best:
            continue
        a, b = scaled[best], scaled[other]
        difference, p = st.welch_test(a, b) if higher else st.welch_test(b, a)
        tests.append(
            {
                "group": group,
                "label": f"{best} vs {other}",
                "test": st.WELCH,
                "difference": difference,
                "log": log,
                "p": p,
                "minimum": minimum(data[other]),
            }
        )
    return best, tests


def table(tests: Sequence[dict[str, Any]]) -> list[str]:
    """Every judged test as the rows of a Markdown table."""
    rows = [
        "| group | comparison | test | difference | minimum | p | Holm p | counts |",
        "| --- | --- | --- | ---: | ---: | ---: | ---: | --- |",
    ]
    for t in tests:
        rows.append(
            f"| {t['group']} | {t['label']} | {t['test']} | {shown(t['difference'], t['log'])}"
            f" | {shown(t['minimum'], t['log'])} | {t['p']:.2g} | {t['adjusted']:.2g} | "
            f"{t['verdict']} |"
        )
    return rows


def seed_panel(ax: Any, columns: Sequence[tuple[str, Sequence[float], str]], log: bool,
               title: str) -> None:  # fmt: skip
    """One metric's panel of a results figure: per column ``(label, per-seed values, colour)``
    each seed as a dot and the mean as a line (geometric on a log axis, where the tests take
    logarithms)."""
    for i, (_, values, colour) in enumerate(columns):
        values = np.asarray(values, dtype=float)
        centre = math.exp(np.nanmean(np.log(values))) if log else np.nanmean(values)
        ax.hlines(centre, i - 0.3, i + 0.3, color=colour, lw=2.5)
        ax.plot(np.full(len(values), i), values, "k.", ms=5)
    rotation = 60 if len(columns) > 4 else 30
    ax.set_xticks(range(len(columns)), [c[0] for c in columns], rotation=rotation, ha="right",
                  fontsize=8)  # fmt: skip
    if log:
        ax.set_yscale("log")
    ax.set_title(title, fontsize=9)
