"""Learning curves of this tree next to those of a reference tree (e.g. the commit before a
redesign), same agents, seeds and preset, in the same run: does the change alter what is
learned?

    python benchmarks/learning_curves.py --reference-src OLD/src [--agents mlp cpg-actor]
        [--seeds 3] [--total-steps 500k] [--preset paper]
        [--output benchmarks/results/learning_curves.md]

Each run is ``cpg-actor train`` in a subprocess (``PYTHONPATH`` = the tree's ``src``), one at
a time, with the tree's own version of the preset (default ``paper``); the curves are the
deterministic evaluations the runs log (``eval/return``, ``eval/hop_height`` in
``metrics.jsonl``). Per agent the report
gives each seed's final evaluation and the mean evaluation over the run (the area under the
curve), and the difference of the two trees' means in units of its standard error (Welch):
|t| < 2 is "within seed noise". The figure is written next to the report (the same name,
``.png``); beside a report named by ``--output``, an existing file of that name is refused
unless ``--overwrite``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

from bench_report import companions
from cpg_actor.config.presets import PRESETS
from cpg_actor.machine import git_commit

HERE = Path(__file__).resolve().parent


def train(
    src: Path, agent: str, seed: int, total_steps: str, run_dir: Path, preset: str = "paper"
) -> list[dict]:
    """One training run with the package in ``src``; its evaluation records."""
    env = dict(os.environ, PYTHONPATH=str(src))
    command = [sys.executable, "-c", "import sys; from cpg_actor.cli import main; sys.exit(main())"]
    command += ["train", "--agent", agent, "--seed", str(seed), "--total-steps", total_steps]
    command += ["--preset", preset, "--run-dir", str(run_dir), "--no-progress"]
    subprocess.run(command, env=env, check=True, capture_output=True, text=True)
    records = [json.loads(line) for line in (run_dir / "metrics.jsonl").read_text().splitlines()]
    return [r for r in records if "eval/return" in r]


def welch_t(a: list[float], b: list[float]) -> float:
    """Welch's t (scipy's): (mean a - mean b) / its standard error; nan with fewer than 2
    values a side or no spread at all."""
    from scipy import stats

    if len(a) < 2 or len(b) < 2:
        return math.nan
    with warnings.catch_warnings():  # identical values: no spread, nan below
        warnings.simplefilter("ignore", RuntimeWarning)
        t = float(stats.ttest_ind(a, b, equal_var=False).statistic)
    return t if math.isfinite(t) else math.nan


def summary(evals: list[dict]) -> dict[str, float]:
    returns = [e["eval/return"] for e in evals]
    return {
        "final_return": returns[-1],
        "final_hop": evals[-1].get("eval/hop_height", math.nan),
        "mean_return": float(np.mean(returns)),
    }


def figure(curves: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    agents = sorted({agent for agent, _, _ in curves})
    fig, axes = plt.subplots(1, len(agents), figsize=(5 * len(agents), 3.6), squeeze=False)
    colors = {"this tree": "tab:blue", "reference": "tab:orange"}
    for ax, agent in zip(axes[0], agents, strict=True):
        for (a, tree, seed), evals in curves.items():
            if a != agent:
                continue
            steps = [e["global_step"] for e in evals]
            label = tree if seed == 0 else None
            ax.plot(steps, [e["eval/return"] for e in evals], color=colors[tree], label=label)
        ax.set_title(agent)
        ax.set_xlabel("env steps")
        ax.set_ylabel("deterministic eval return")
        ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reference-src", required=True, help="src/ of the reference tree")
    parser.add_argument("--agents", nargs="+", default=["mlp", "cpg-actor"])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--total-steps", default="500k")
    parser.add_argument(
        "--preset", default="paper", choices=sorted(PRESETS), help="the preset of both trees"
    )
    default_output = str(HERE / "results" / "learning_curves.md")
    parser.add_argument(
        "--output",
        default=default_output,
        help="the report; its figure goes beside it (the same name, .png)",
    )
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="replace an existing figure beside a named --output",
    )
    args = parser.parse_args()
    (figure_path,) = companions(parser, args.output, (".png",), args.output != default_output,
                                args.overwrite)  # fmt: skip
    trees = {"this tree": HERE.parent / "src", "reference": Path(args.reference_src).resolve()}
    commits = {tree: git_commit(src) for tree, src in trees.items()}  # the code the runs use
    curves: dict[tuple[str, str, int], list[dict]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for agent in args.agents:
            for seed in range(args.seeds):
                for tree, src in trees.items():
                    run_dir = Path(tmp) / f"{agent}-{tree.replace(' ', '_')}-{seed}"
                    curves[agent, tree, seed] = train(
                        src, agent, seed, args.total_steps, run_dir, args.preset
                    )
                    s = summary(curves[agent, tree, seed])
                    print(f"{agent} {tree} seed {seed}: {s}", flush=True)
    output = Path(args.output)
    output.parent.mkdir(parents=True, exist_ok=True)
    figure(curves, figure_path)
    lines = [
        "# Learning curves: this tree against a reference tree",
        "",
        f"Measured {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC with "
        f"`python benchmarks/learning_curves.py --reference-src REF/src --agents "
        f"{' '.join(args.agents)} --seeds {args.seeds} --total-steps {args.total_steps}"
        f"{'' if args.preset == 'paper' else ' --preset ' + args.preset}`: this "
        f"tree at commit {commits['this tree']}, REF at commit "
        f"{commits['reference']} (at the start); each tree's `{args.preset}` preset, seeds "
        f"0..{args.seeds - 1}. Figure: `{output.with_suffix('.png').name}`.",
        "",
        "| agent | tree | final eval return per seed | mean | final hop height (m) | "
        "mean eval return over the run |",
        "| --- | --- | --- | ---: | ---: | ---: |",
    ]
    verdicts = []
    for agent in args.agents:
        stats = {}
        for tree in trees:
            runs = [summary(curves[agent, tree, seed]) for seed in range(args.seeds)]
            stats[tree] = runs
            finals = [r["final_return"] for r in runs]
            lines.append(
                f"| {agent} | {tree} | {', '.join(f'{v:.0f}' for v in finals)} | "
                f"{np.mean(finals):.0f} +- {np.std(finals, ddof=1) if len(finals) > 1 else 0:.0f}"
                f" | {np.mean([r['final_hop'] for r in runs]):.3f} | "
                f"{np.mean([r['mean_return'] for r in runs]):.0f} |"
            )
        for key, name in (("final_return", "final return"), ("mean_return", "mean return")):
            t = welch_t([r[key] for r in stats["this tree"]], [r[key] for r in stats["reference"]])
            verdict = "within seed noise" if abs(t) < 2 else "differs"
            verdicts.append(f"- {agent}, {name}: Welch t = {t:+.2f} ({verdict}).")
    lines += ["", *verdicts, ""]
    output.write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
