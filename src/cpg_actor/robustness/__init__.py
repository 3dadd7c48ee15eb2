"""The robustness suite (``cpg-actor robustness``, ``docs/robustness.md``): trained policies
evaluated deterministically under each perturbation their robot declares
(:class:`~cpg_actor.robots.common.perturbation.PerturbationTable`), at each level and
nominally; per run, then per variant over seeds with bootstrap CIs; ``robustness.json``,
``robustness.md`` and a figure per perturbation.

* :mod:`~cpg_actor.robustness.runs`: the runs of the arguments (runs, reproductions);
* :mod:`~cpg_actor.robustness.recovery`: how long a push takes to be recovered from;
* :mod:`~cpg_actor.robustness.suite`: one run under every level;
* :mod:`~cpg_actor.robustness.summary`: per variant, the files.
"""
