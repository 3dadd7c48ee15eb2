"""Claims and their verdicts: a claim's tests must all pass after the family's correction
(:func:`decide`), or it has a fixed verdict (not tested, undefined).

* **supported**: every test of the claim passes (Holm-adjusted p < ``ALPHA``, difference in
  the claimed direction and at least the minimum effect) and the claim's other conditions
  hold; the verdict's text names the test, the family size and the correction.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from cpg_actor.statistics.intervals import MIN_SEEDS, seeds_with_data
from cpg_actor.statistics.testing import ALPHA, HOLM, Test, holm

SUPPORTED = "supported"
NOT_SUPPORTED = "not supported"
NOT_TESTED = "not tested in this run"
Verdict = tuple[str, str]  # (verdict, explanation)


@dataclass
class Claim:
    """A claim's evidence before its family's correction: the ``tests`` that must all pass,
    ``condition`` (its other conditions hold), the text (``evidence``: estimates and bootstrap
    CIs, for display; ``rule``: what "supported" needs besides the tests); or a verdict
    ``fixed`` without tests (not tested, undefined)."""

    evidence: str
    tests: list[Test] = field(default_factory=list)
    condition: bool = True
    rule: str = ""
    fixed: str | None = None


def family_text(size: int, alpha: float = ALPHA) -> str:
    return f"{HOLM} correction over a family of {size} tests at alpha {alpha:g}"


def decide(claims: Sequence[Claim], alpha: float = ALPHA) -> list[Verdict]:
    """The verdicts of a report's claims, one family: the p-values of every test of every
    claim (those not ``fixed``) are Holm-corrected together; a claim is supported when each of
    its tests passes (:meth:`Test.passed`) and its ``condition`` holds. Each explanation names
    the tests, the family's size and the correction."""
    tests = [test for claim in claims if claim.fixed is None for test in claim.tests]
    for test, adjusted in zip(tests, holm([test.p for test in tests]), strict=True):
        test.adjusted = adjusted
    verdicts = []
    for claim in claims:
        if claim.fixed is not None:
            verdicts.append((claim.fixed, claim.evidence))
            continue
        ok = claim.condition and all(test.passed(alpha) for test in claim.tests)
        names = ", ".join(dict.fromkeys(test.name for test in claim.tests))
        rule = f"; {claim.rule}" if claim.rule else ""
        text = (
            f"{claim.evidence}; {names}: " + "; ".join(map(str, claim.tests))
            + f" ({family_text(len(tests), alpha)}; supported if every {HOLM} p < {alpha:g} "
            f"with the difference above 0 and its minimum{rule})"
        )  # fmt: skip
        verdicts.append((SUPPORTED if ok else NOT_SUPPORTED, text))
    return verdicts


Groups = Mapping[str, Sequence[float] | None]


def too_few_seeds(groups: Groups) -> Claim | None:
    """ "Not tested" when a group (a variant's per-seed values; None: not run) has fewer than
    :data:`MIN_SEEDS` finite values, with every group's count; None when all have enough."""
    counts = {name: seeds_with_data(values) for name, values in groups.items()}
    if groups and all(count >= MIN_SEEDS for count in counts.values()):
        return None
    parts = [
        f"{name} not run" if groups[name] is None else f"{name} {count}"
        for name, count in counts.items()
    ]
    return Claim(
        f"needs at least {MIN_SEEDS} seeds with data for each of "
        f"{', '.join(counts) or 'the variants'}; seeds here: {', '.join(parts) or 'none'}",
        fixed=NOT_TESTED,
    )
