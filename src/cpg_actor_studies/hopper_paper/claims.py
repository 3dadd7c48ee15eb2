"""The paper's claims about the hopper (Campanaro et al., sections IV and V), each a function
of the per-seed numbers that returns its evidence and tests (:class:`cpg_actor.statistics.Claim`),
and :func:`judge_claims`, which judges them all as one family (:func:`cpg_actor.statistics.decide`).

The hopper's motor limit, ``VELOCITY_LIMIT`` (15 rad/s, the paper's section IV), is the limit of
the desired-velocity claim.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from cpg_actor.statistics import (
    BAND,
    MIN_SEEDS,
    MINIMUM_EFFECT,
    NOT_SUPPORTED,
    NOT_TESTED,
    PAIRED,
    Claim,
    Groups,
    Interval,
    Test,
    band_test,
    better_test,
    bootstrap,
    bootstrap_difference,
    bootstrap_ratio,
    decide,
    finite,
    paired_t_test,
    ratio_test,
    seeds_with_data,
    too_few_seeds,
)
from cpg_actor_studies.reproduction.results import agent_kind

VELOCITY_LIMIT = 15.0  # rad/s, the hopper's motor limit (paper section IV)
PAPER_COMPARISON_STEPS = 20_000_000  # "roughly six times more reward after 20 million steps"
PAPER_STAGE_STEPS = (1_000_000, 20_000_000, 60_000_000)


def verdict_reward_ratio(
    cpg: Sequence[float] | None, cho: Sequence[float] | None, target: float = 6.0
) -> Claim:
    """ "About 6x the reward of Cho et al. (warm)": the ratio of mean final returns over seeds
    is within a factor 2 of ``target`` and the CPG-Actor's return is higher (Welch's t-test,
    :data:`MINIMUM_EFFECT` of returns); the ratio's unpaired bootstrap CI is shown."""
    missing = too_few_seeds({"cpg-actor": cpg, "cho2019-warm": cho})
    if missing:
        return missing
    ratio = bootstrap_ratio(cpg, cho)
    if ratio is None:
        return Claim("ratio undefined (Cho et al. (warm) return not positive)",
                     fixed=NOT_SUPPORTED)  # fmt: skip
    return Claim(
        f"ratio of means {ratio}",
        [better_test(cpg, cho, "return", "cpg-actor - cho2019-warm")],
        target / 2 <= ratio.estimate <= target * 2,
        f"the ratio of means within [{target / 2:g}, {target * 2:g}]",
    )


def verdict_better(open_loop: Sequence[float] | None, cho: Groups) -> Claim:
    """ "Open-loop CPG-Actor beats Cho et al.": its mean final return is higher than every Cho
    et al. variant's that ran (``cho``: variant -> per-seed final returns), by Welch's t-test
    and the minimum effect of returns."""
    if not cho:
        return Claim("needs cpg-actor-open-loop and cho2019-warm, cho2019 or cho2019-paper",
                     fixed=NOT_TESTED)  # fmt: skip
    missing = too_few_seeds({"cpg-actor-open-loop": open_loop, **cho})
    if missing:
        return missing
    parts = [
        f"vs {name}: {bootstrap_difference(open_loop, values)}" for name, values in cho.items()
    ]
    return Claim(
        "difference of mean final returns " + "; ".join(parts),
        [better_test(open_loop, values, "return", f"cpg-actor-open-loop - {name}")
         for name, values in cho.items()],
    )  # fmt: skip


def ratio_of_medians(larger: Sequence[float], smaller: Sequence[float]) -> Interval | None:
    """``median(larger) / median(smaller)`` over seeds with an unpaired bootstrap CI, for a
    claim that ``larger`` is many times ``smaller``. Resampled as ``smaller / larger`` and
    inverted (a percentile interval inverts with it), so that a ``smaller`` of 0 (perfectly
    flat) gives an infinite ratio rather than none; None when ``larger``'s median, or a
    resampled one, is not positive (then the claim cannot hold)."""
    inverse = bootstrap_ratio(smaller, larger, statistic="median")
    if inverse is None:
        return None
    with np.errstate(divide="ignore"):
        low, high, estimate = np.divide(1.0, [inverse.high, inverse.low, inverse.estimate])
    return Interval(float(estimate), float(low), float(high))


def verdict_smooth(
    cpg: Sequence[float] | None, mlp: Sequence[float] | None, factor: float = 10.0
) -> Claim:
    """ "CPG outputs are smooth where the MLP is bang-bang": the MLP's mean smoothness (squared
    second difference) is more than ``factor`` times the CPG-Actor's, by Welch's t-test of
    ``mean(mlp) - factor * mean(cpg)`` (unpaired: the two agents' seeds are independent runs).
    The medians over seeds and their ratio with its bootstrap CI (:func:`ratio_of_medians`)
    are shown, as one rough seed can carry a mean."""
    missing = too_few_seeds({"cpg-actor": cpg, "mlp": mlp})
    if missing:
        return missing
    ratio = ratio_of_medians(mlp, cpg)
    cpg_median, mlp_median = np.median(finite(cpg)), np.median(finite(mlp))
    ratio_text = ratio if ratio is not None else "undefined (the MLP's median is 0: flat)"
    return Claim(
        f"median squared 2nd difference {cpg_median:.3g} (CPG-Actor) vs {mlp_median:.3g} rad^2 "
        f"(MLP), ratio of medians MLP / CPG-Actor {ratio_text}",
        [ratio_test(mlp, cpg, factor, f"mean MLP - {factor:g} x mean CPG-Actor")],
    )


def verdict_near_limits(
    p99: Sequence[float] | None,
    share: Sequence[float] | None = None,
    limit: float = VELOCITY_LIMIT,
    band: tuple[float, float] = (0.6, 1.2),
) -> Claim:
    """ "Desired velocities stay near the motor limits": the mean over seeds of the per-seed
    99th percentile of |desired velocity| lies inside ``band`` x the limit (the range is
    used, and only just exceeded if at all), by two one-sided t-tests (:func:`band_test`).
    The median over seeds with its bootstrap CI is shown; ``share``: per-seed shares within
    the limit, shown only."""
    missing = too_few_seeds({"cpg-actor": p99})
    if missing:
        return missing
    median = bootstrap(p99, "median")
    low, high = band[0] * limit, band[1] * limit
    within = finite(share)
    within_text = (
        f", median {100 * np.median(within):.1f}% within +-{limit:g} rad/s" if within.size else ""
    )
    distance, p = band_test(p99, low, high)
    label = f"mean {np.mean(finite(p99)):.3g} rad/s inside [{low:g}, {high:g}], margin"
    return Claim(f"p99 |v| median over seeds {median} rad/s{within_text}",
                 [Test(BAND, label, distance, p)])  # fmt: skip


def verdict_hop_doubles(
    final: Sequence[float] | None,
    early: Sequence[float] | None,
    early_step: float,
    total_steps: float,
    threshold: float = 1.5,
) -> Claim:
    """ "The hop height about doubles with training" (paper: 1M -> 60M steps): the CPG-Actor's
    mean hop height in the deterministic evaluations at the end over that at ``early_step``
    (1M), per seed ``final[i]`` and ``early[i]`` of the same run, is >= ``threshold``, and the
    hop height rose (paired t-test: the same runs measured at two times; the minimum effect of
    hop heights). The ratio's paired bootstrap CI is shown. Judged only on runs of at least
    twice ``early_step``: the hop height of an untrained agent is no baseline."""
    if total_steps < 2 * early_step:
        return Claim(
            f"needs runs of at least {2 * early_step:,.0f} steps (the paper compares "
            f"{early_step:,.0f} steps with the end); this run: {total_steps:,.0f}",
            fixed=NOT_TESTED,
        )
    if final is None or early is None:
        return Claim("needs cpg-actor", fixed=NOT_TESTED)
    a, b = np.asarray(final, dtype=float), np.asarray(early, dtype=float)
    keep = np.isfinite(a) & np.isfinite(b) if a.shape == b.shape else np.zeros(0, bool)
    pairs = int(keep.sum())
    if pairs < MIN_SEEDS:
        return Claim(
            f"needs at least {MIN_SEEDS} cpg-actor seeds with hop heights logged at "
            f"{early_step:,.0f} steps and at the end; seeds here: {pairs}",
            fixed=NOT_TESTED,
        )
    ratio = bootstrap_ratio(a, b, paired=True)
    if ratio is None:
        return Claim(f"ratio undefined (hop height at {early_step:,.0f} steps not positive)",
                     fixed=NOT_TESTED)  # fmt: skip
    difference, p = paired_t_test(a, b)
    minimum = MINIMUM_EFFECT["hop_height"].threshold(float(b[keep].mean()))
    return Claim(
        f"hop height at the end / at {early_step:,.0f} steps, ratio of means over {pairs} "
        f"seeds, paired: x{ratio}",
        [Test(PAIRED, "end - early (m)", difference, p, minimum)],
        ratio.estimate >= threshold,
        f"the ratio of means >= x{threshold:g}",
    )


def verdict_best_during_training(cpg: Sequence[float] | None, others: Groups) -> Claim:
    """ "The CPG-Actor performs best during training": its mean evaluation return over the
    whole run (the area under the curve, per seed) is higher than every other variant's
    (``others``: variant -> per-seed values), each by Welch's t-test and the minimum effect of
    returns."""
    if not others:
        return Claim("needs cpg-actor and another variant with evaluation curves",
                     fixed=NOT_TESTED)  # fmt: skip
    missing = too_few_seeds({"cpg-actor": cpg, **others})
    if missing:
        return missing
    parts = [f"vs {name}: {bootstrap_difference(cpg, values)}" for name, values in others.items()]
    return Claim(
        "mean eval return over the run, difference of means " + "; ".join(parts),
        [better_test(cpg, values, "return", f"cpg-actor - {name}")
         for name, values in others.items()],
    )  # fmt: skip


CPG_SIGNALS = ("theta_dot", "r_ddot")


def verdict_cho_flat(
    cpg: Mapping[str, Sequence[float]] | None,
    cho: Mapping[str, Mapping[str, Sequence[float]]],
    factor: float = 3.0,
) -> Claim:
    """ "Cho et al.'s theta_dot and r_ddot stay almost flat (not responsive to the
    environment) where the CPG-Actor's are reshaped by feedback" (paper section V): for both
    signals and every Cho variant, the CPG-Actor's mean per-seed :func:`variability` is more
    than ``factor`` times Cho's (Welch's t-test of ``mean(cpg) - factor * mean(cho)``,
    unpaired). The ratio of medians with its bootstrap CI (:func:`ratio_of_medians`) is shown.
    ``cpg`` and each ``cho[variant]`` map ``theta_dot`` and ``r_ddot`` to per-seed values."""
    if not cho:
        return Claim("needs cpg-actor and a Cho et al. variant with CPG traces", fixed=NOT_TESTED)
    groups: dict[str, Sequence[float] | None] = {}
    for name in CPG_SIGNALS:
        groups[f"cpg-actor {name}"] = None if cpg is None else cpg[name]
        for variant, values in cho.items():
            groups[f"{variant} {name}"] = values[name]
    missing = too_few_seeds(groups)
    if missing:
        return missing
    parts, tests = [], []
    for variant, values in cho.items():
        for name in CPG_SIGNALS:
            ratio = ratio_of_medians(cpg[name], values[name])
            text = ratio if ratio else "undefined (the CPG-Actor's median is 0 on resampled seeds)"
            parts.append(f"{name} CPG-Actor / {variant}: {text}")
            label = f"{name} mean CPG-Actor - {factor:g} x mean {variant}"
            tests.append(ratio_test(cpg[name], values[name], factor, label))
    cpg_text = ", ".join(f"{name} {np.median(finite(cpg[name])):.3g}" for name in CPG_SIGNALS)
    return Claim(
        f"median std over an episode: CPG-Actor {cpg_text} (rad/s, rad/s^2); ratio of medians "
        + "; ".join(parts),
        tests,
    )


def judge_claims(
    seeds: dict[str, dict[str, list[float]]], rewards: dict[str, str], total_steps: int
) -> list[dict[str, str]]:
    """The paper's claims judged on the per-seed numbers (``seeds``: variant -> key -> values,
    as ``summary.json``'s ``per_seed``; ``rewards``: variant -> :func:`reward_of`) of runs of
    ``total_steps``: each claim's verdict and detail, all claims one family
    (:func:`cpg_actor.statistics.decide`)."""
    comparison_step = min(total_steps, PAPER_COMPARISON_STEPS)
    variants = list(seeds)

    def per_seed(variant: str, key: str) -> list[float] | None:
        """A variant's per-seed values; None when it did not run."""
        return seeds[variant][key] if variant in seeds else None

    cho_variants = [variant for variant in variants if agent_kind(variant) == "cho"]
    # the claims (claim, its evidence, a prefix of its explanation), judged as one family
    claims: list[tuple[str, Claim, str]] = []
    # 1. about 6x the reward of Cho et al. (warm)
    claims.append(
        (
            "CPG-Actor reaches about 6x the reward of Cho et al. (warm) after 20M steps",
            verdict_reward_ratio(
                per_seed("cpg-actor", "return_at_comparison"),
                per_seed("cho2019-warm", "return_at_comparison"),
            ),
            f"final returns at {comparison_step:,} steps: ",
        )
    )
    # 2. open-loop CPG-Actor beats Cho et al.
    claims.append(
        (
            "the open-loop CPG-Actor beats Cho et al.",
            verdict_better(
                per_seed("cpg-actor-open-loop", "final_return"),
                {cho: per_seed(cho, "final_return") for cho in cho_variants},
            ),
            "final returns: ",
        )
    )
    # 3. smooth vs bang-bang
    claims.append(
        (
            "CPG-Actor desired positions are smooth where the MLP actor is bang-bang",
            verdict_smooth(per_seed("cpg-actor", "smoothness"), per_seed("mlp", "smoothness")),
            "",
        )
    )
    # 4. near the motor limits
    claims.append(
        (
            "CPG-Actor desired velocities stay near (within) the +-15 rad/s motor limits",
            verdict_near_limits(
                per_seed("cpg-actor", "velocity_p99"), per_seed("cpg-actor", "velocity_share")
            ),
            "",
        )
    )
    # 5. the hop height about doubles: 1M steps -> the end, as in the paper (1M -> 60M)
    claims.append(
        (
            "the CPG-Actor's hop height about doubles with training (1M -> 60M steps in the paper; "
            "here 1M -> the end)",
            verdict_hop_doubles(
                per_seed("cpg-actor", "final_hop_height_logged"),
                per_seed("cpg-actor", "hop_height_at_1M"),
                PAPER_STAGE_STEPS[0],
                total_steps,
            ),
            "",
        )
    )
    # 6. the CPG-Actor performs best during training (paper Fig. 6)
    # against the variants trained on the same reward only (returns of other rewards differ),
    # and with evaluation curves logged
    others = {
        other: seeds[other]["mean_eval_return"]
        for other in variants
        if other != "cpg-actor"
        and "cpg-actor" in variants
        and rewards[other] == rewards["cpg-actor"]
        and seeds_with_data(seeds[other]["mean_eval_return"])
    }
    claims.append(
        (
            "the CPG-Actor performs best during training",
            verdict_best_during_training(per_seed("cpg-actor", "mean_eval_return"), others),
            "",
        )
    )

    # 7. Cho et al.'s theta_dot and r_ddot stay flat; the CPG-Actor's respond (section V)
    def flatness(variant: str) -> dict[str, list[float]] | None:
        if variant not in seeds:
            return None
        return {n: seeds[variant][f"{n}_variability"] for n in CPG_SIGNALS}

    claims.append(
        (
            "Cho et al.'s theta_dot and r_ddot stay almost flat, the CPG-Actor's are reshaped by "
            "its feedback",
            verdict_cho_flat(flatness("cpg-actor"), {cho: flatness(cho) for cho in cho_variants}),
            "",
        )
    )
    verdicts = decide([claim for _, claim, _ in claims])
    return [
        {"claim": claim, "verdict": verdict, "detail": prefix + detail}
        for (claim, _, prefix), (verdict, detail) in zip(claims, verdicts, strict=True)
    ]
