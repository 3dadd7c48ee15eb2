"""One module per `cpg-actor` sub-command (see `cpg_actor.cli`), and the options they share."""

from __future__ import annotations

import argparse


def add_set_option(parser: argparse.ArgumentParser, help: str) -> None:
    """``--set KEY=VALUE`` (repeatable) into ``args.overrides``: a config value on its dotted
    path, read as YAML (see :func:`cpg_actor.config.parse_override`)."""
    parser.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE", help=help
    )
