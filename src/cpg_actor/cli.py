"""The `cpg-actor` command line: one sub-command per module in `cpg_actor.commands`.

Each command module defines `HELP` (one line), `add_arguments(parser)` and `run(args) -> int`.
Modules are imported only when their command runs, so `cpg-actor --help` stays fast.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from cpg_actor.machine import brief_openmp_spinning

brief_openmp_spinning(os.environ)  # before anything imports torch

from cpg_actor.envs.mjx.runtime import MjxUnavailable  # noqa: E402
from cpg_actor.envs.video import RenderingUnavailable  # noqa: E402

# command name -> module in cpg_actor.commands
COMMANDS: dict[str, str] = {
    "cpg-demo": "cpg_demo",
    "gaits": "gaits",
    "train": "train",
    "eval": "eval",
    "export": "export",
    "cho2019-reference": "cho2019_reference",
    "reproduce": "reproduce",
    "sweep": "sweep",
    "figures": "figures",
    "curves": "curves",
    "gradient": "gradient",
    "transfer": "transfer",
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cpg-actor",
        description="Train Central Pattern Generator controllers with deep RL (CPG-Actor).",
    )
    from cpg_actor import __version__

    parser.add_argument("--version", action="version", version=f"cpg-actor {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, module_name in COMMANDS.items():
        module = importlib.import_module(f"cpg_actor.commands.{module_name}")
        command_parser = sub.add_parser(name, help=module.HELP, description=module.HELP)
        module.add_arguments(command_parser)
        command_parser.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args._run(args) or 0)
    except (
        ValueError, FileNotFoundError, FileExistsError, NotADirectoryError, MjxUnavailable,
    ) as error:  # fmt: skip
        print(f"cpg-actor {args.command}: error: {error}", file=sys.stderr)
        return 2
    # unwritable or full disk, read-only file system, no OpenGL to render with...: one line
    except (OSError, RenderingUnavailable) as error:
        print(f"cpg-actor {args.command}: error: {error}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
