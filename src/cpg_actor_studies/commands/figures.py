"""`cpg-actor figures`: redraw the figures and the report of an existing results directory."""

from __future__ import annotations

import argparse
from pathlib import Path

HELP = "redraw the paper's figures and report.md from a `cpg-actor reproduce` results directory"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("out", help="results directory written by `cpg-actor reproduce`")
    parser.add_argument(
        "--floor",
        action="store_true",
        help="compute the open-loop grid floor first if OUT has none (about a minute)",
    )


def run(args: argparse.Namespace) -> int:
    from cpg_actor_studies.hopper_paper.report import write_report
    from cpg_actor_studies.reproduction.plan import SETTINGS_FILE

    out = Path(args.out)
    if not (out / SETTINGS_FILE).is_file() and not (out / "runs").is_dir():
        raise FileNotFoundError(f"{out} is not a reproduce results directory (no {SETTINGS_FILE})")
    if args.floor:
        from cpg_actor_studies.hopper_paper.floor import ensure_floor
        from cpg_actor_studies.reproduction.plan import ReproduceSettings, load_settings_file

        saved = (load_settings_file(out) or {}).get("settings")
        if not saved:
            raise ValueError(f"--floor needs the settings of {out} ({SETTINGS_FILE})")
        fields = ReproduceSettings.__dataclass_fields__
        ensure_floor(out, ReproduceSettings(**{k: v for k, v in saved.items() if k in fields}))
    report = write_report(out)
    print(f"report {report}; figures in {out / 'figures'}")
    return 0
