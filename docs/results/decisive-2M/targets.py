"""The 2M-step targets of issue "The CPG-Actor at its best", judged on this folder's summary.

    python docs/results/decisive-2M/targets.py docs/results/decisive-2M/summary.json

Per-seed numbers are the final deterministic evaluation's (``eval_return`` and ``hop_height``
from the evaluation traces, ``final_return`` from the logged evaluations), with percentile
bootstrap CIs over the 5 report seeds (`cpg_actor.statistics`).
"""

from __future__ import annotations

import sys

from cpg_actor.api import statistics as st
from cpg_actor.inputs import read_json, run_script

SUMMARY = "the summary.json cpg-actor reproduce writes"


def main(path: str) -> None:
    seeds = {name: row["per_seed"] for name, row in read_json(path, SUMMARY)["variants"].items()}
    cpg, mlp, cho, es = (seeds[v] for v in ("cpg-actor", "mlp", "cho2019-warm", "open-loop-es"))
    rows = []

    def judge(target: str, interval: st.Interval | None, at_least: float, sign: int = 1) -> None:
        """met: the whole CI on the target's side of ``at_least`` (``sign`` -1: at most);
        missed: the whole CI on the other side; otherwise not resolved."""
        if interval is None:
            verdict = "not tested"
        elif min(sign * interval.low, sign * interval.high) >= sign * at_least:
            verdict = "met"
        elif max(sign * interval.low, sign * interval.high) < sign * at_least:
            verdict = "missed"
        else:
            verdict = "not resolved"
        rows.append(f"| {target} | {interval} | **{verdict}** |")

    judge("hop height >= 2x `mlp`'s (ratio of means)",
          st.bootstrap_ratio(cpg["hop_height"], mlp["hop_height"]), 2.0)  # fmt: skip
    judge("hop height >= `cho2019-warm`'s (difference of means, m)",
          st.bootstrap_difference(cpg["hop_height"], cho["hop_height"]), 0.0)  # fmt: skip
    judge("p99 desired velocity <= 15 rad/s (median over seeds)",
          st.bootstrap(cpg["velocity_p99"], "median"), 15.0, sign=-1)  # fmt: skip
    smooth = st.bootstrap_ratio(mlp["smoothness"], cpg["smoothness"], statistic="median")
    judge(">= 10x smoother than `mlp` (ratio of medians, mean squared 2nd difference)",
          smooth, 10.0)  # fmt: skip
    judge("return >= `mlp`'s (difference of means)",
          st.bootstrap_difference(cpg["final_return"], mlp["final_return"]), 0.0)  # fmt: skip
    judge("return > `open-loop-es`'s by its CI (difference of means)",
          st.bootstrap_difference(cpg["final_return"], es["final_return"]), 0.0)  # fmt: skip
    print("| target | estimate [95 % CI] | verdict |\n| --- | --- | --- |")
    print("\n".join(rows))
    print(
        "\nmet: the whole CI on the target's side; missed: the whole CI on the other side; "
        "not resolved: the CI holds the target."
    )


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(f"usage: python {sys.argv[0]} SUMMARY.json")
    sys.exit(run_script(lambda: main(sys.argv[1]), "decisive-2M/targets.py"))
