"""`cpg-actor cho2019-reference`: search the reference hopping CPG parameters of the baseline.

Runs :func:`cpg_actor.robots.hopper.cho2019_reference.search_reference` on the default grid (960
constant parameter sets, open loop, one episode each) and prints the best ones and the chosen
reference, which is what :data:`REFERENCE_PARAMETERS` ships.
"""

from __future__ import annotations

import argparse

HELP = "grid-search the reference hopping CPG parameters that warm-start the cho2019 baseline"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--sim", choices=("mujoco", "pybullet"), default="mujoco")
    parser.add_argument("--top", type=int, default=10, help="how many candidates to print")


def run(args: argparse.Namespace) -> int:
    from rich.console import Console
    from rich.table import Table

    from cpg_actor.robots.hopper.cho2019 import PARAMETER_NAMES
    from cpg_actor.robots.hopper.cho2019_reference import (
        REFERENCE_PARAMETERS,
        choose_reference,
        describe,
        interior,
        search_reference,
    )
    from cpg_actor.robots.hopper.config import HopperConfig

    if args.top < 1:
        raise ValueError(f"--top must be >= 1, got {args.top}")
    console = Console()
    with console.status("running the grid (one episode per candidate)..."):
        candidates = search_reference(config=HopperConfig(sim=args.sim))
    table = Table(title=f"best of {len(candidates)} constant CPG parameter sets ({args.sim})")
    for name in (*PARAMETER_NAMES, "hop height (m)", "return", "inside range"):
        table.add_column(name, justify="right")
    for c in candidates[: args.top]:
        table.add_row(
            *(f"{v:.3f}" for v in c.parameters),
            f"{c.hop_height:.3f}",
            f"{c.episode_return:.1f}",
            "yes" if interior(c) else "no",
        )
    console.print(table)
    chosen = choose_reference(candidates)
    console.print(f"reference: {describe(chosen.parameters)} (hop {chosen.hop_height:.3f} m)")
    shipped = tuple(round(v, 6) for v in REFERENCE_PARAMETERS)
    same = shipped == tuple(round(v, 6) for v in chosen.parameters)
    console.print(
        f"shipped REFERENCE_PARAMETERS: {describe(REFERENCE_PARAMETERS)} "
        f"({'same' if same else 'DIFFERENT: update cpg_actor/robots/hopper/cho2019_reference.py'})"
    )
    return 0
