"""The studies' `cpg-actor` sub-commands, one module each (``HELP``, ``add_arguments(parser)``,
``run(args) -> int``, as :mod:`cpg_actor.cli` describes); :data:`COMMANDS` registers them with
the command line, which imports this module when the studies are installed
(:data:`cpg_actor.cli.PLUGINS`)."""

# command name -> (its module, its HELP), as :data:`cpg_actor.cli.COMMANDS`
COMMANDS: dict[str, tuple[str, str]] = {
    "reproduce": (
        "cpg_actor_studies.commands.reproduce",
        "reproduce the paper: train variants x seeds in parallel (or on Ray), figures and a report",
    ),
    "sweep": (
        "cpg_actor_studies.commands.sweep",
        "sensitivity study: train variants x seeds for the defaults and each --vary setting",
    ),
    "figures": (
        "cpg_actor_studies.commands.figures",
        "redraw the paper's figures and report.md from a `cpg-actor reproduce` results directory",
    ),
    "curves": (
        "cpg_actor_studies.commands.curves",
        "draw the learning curves of several runs (grouped by agent and settings) in one figure",
    ),
    "gradient": (
        "cpg_actor_studies.commands.gradient",
        "measure the k-step (truncated) CPG gradient against the full-trajectory one",
    ),
    "transfer": (
        "cpg_actor_studies.commands.transfer",
        "evaluate a reproduction's final policies in both simulators (cross-simulator transfer)",
    ),
}
