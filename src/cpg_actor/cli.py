"""The `cpg-actor` command line: one sub-command per module in `cpg_actor.commands`, then the
commands of the packages in :data:`PLUGINS` that are installed (the studies' commands:
``cpg_actor_studies.commands``), then the robots' own.

Each command module defines `HELP` (one line), `add_arguments(parser)` and `run(args) -> int`.
Only the module of the command being run is imported (its arguments are added to that
command's parser alone), so `cpg-actor --help` and `--version` import neither torch nor a
simulator; `COMMANDS` repeats each module's `HELP` for the list of commands (a test checks
they agree).
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import os
import sys

from cpg_actor.machine import brief_openmp_spinning, die_with_parent

brief_openmp_spinning(os.environ)  # before anything imports torch

from cpg_actor.errors import MjxUnavailable, RenderingUnavailable  # noqa: E402
from cpg_actor.files import describe_os_error  # noqa: E402

# command name -> (its module, its HELP); the plugins' and the robots' commands follow
# (commands())
COMMANDS: dict[str, tuple[str, str]] = {
    "gaits": (
        "cpg_actor.commands.gaits",
        "run a quadruped's CPG gait presets open loop; write a gait diagram and a summary",
    ),
    "train": (
        "cpg_actor.commands.train",
        "train an agent (cpg-actor, cpg-actor-paper, mlp, mlp-warm, cho2019-warm, ...) with "
        "PPO, or search one (open-loop-es: CMA-ES)",
    ),
    "eval": (
        "cpg_actor.commands.eval",
        "evaluate a trained run deterministically; save per-step traces, figures (and a video)",
    ),
    "export": (
        "cpg_actor.commands.export",
        "export a trained policy (normaliser, networks, CPG step) as TorchScript or ONNX",
    ),
    "robustness": (
        "cpg_actor.commands.robustness",
        "evaluate trained runs under perturbations (pushes, payload, friction, latency, ...)",
    ),
}


# modules that add commands: each holds a table ``COMMANDS`` like :data:`COMMANDS`, and is
# imported only when its package is installed (by name here, never by an import statement: the
# studies sit above the library, tests/test_layers.py)
PLUGINS = ("cpg_actor_studies.commands",)


def commands() -> dict[str, tuple[str, str]]:
    """Every command: the generic ones (:data:`COMMANDS`), then those of the installed
    :data:`PLUGINS`, then those the robots bring (``Robot.commands``, in the registry's
    order)."""
    from cpg_actor.robots.registry import ROBOTS

    merged = dict(COMMANDS)
    for plugin in PLUGINS:
        if importlib.util.find_spec(plugin.split(".")[0]) is not None:
            merged.update(importlib.import_module(plugin).COMMANDS)
    for robot in ROBOTS.values():
        merged.update(robot.commands)
    return merged


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser: every command listed with its help; ``command``'s module imported and its
    arguments added (the others are not parsed in this run)."""
    parser = argparse.ArgumentParser(
        prog="cpg-actor",
        description="Train Central Pattern Generator controllers with deep RL (CPG-Actor).",
    )
    from cpg_actor import __version__

    parser.add_argument("--version", action="version", version=f"cpg-actor {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, (module_name, help_text) in commands().items():
        command_parser = sub.add_parser(name, help=help_text, description=help_text)
        if name == command:
            module = importlib.import_module(module_name)
            module.add_arguments(command_parser)
            command_parser.set_defaults(_run=module.run)
    return parser


def _command(argv: list[str]) -> str | None:
    """The command named in ``argv``: its first word that is not an option (the only
    options before it, -h and --version, take no value)."""
    return next((word for word in argv if not word.startswith("-")), None)


def main(argv: list[str] | None = None) -> int:
    die_with_parent(os.environ)  # a run of reproduce or sweep: not an orphan if it is killed
    argv = list(sys.argv[1:] if argv is None else argv)
    args = build_parser(_command(argv)).parse_args(argv)
    try:
        return int(args._run(args) or 0)
    except (
        ValueError, FileNotFoundError, FileExistsError, NotADirectoryError, MjxUnavailable,
    ) as error:  # fmt: skip
        print(f"cpg-actor {args.command}: error: {error}", file=sys.stderr)
        return 2
    # unwritable or full disk, read-only file system, no OpenGL to render with...: one line
    except (OSError, RenderingUnavailable) as error:
        text = describe_os_error(error) if isinstance(error, OSError) else str(error)
        print(f"cpg-actor {args.command}: error: {text}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
