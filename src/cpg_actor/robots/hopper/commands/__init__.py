"""The hopper's own `cpg-actor` commands (its ``Robot.commands``): the CPG demo and the search
of the Cho et al. baseline's reference parameters. At the command line's layer; the CLI finds
them through the registry entry, by module name."""
