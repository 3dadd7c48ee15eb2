"""The studies of the CPG-Actor method, apart from the library (``cpg_actor``) they use as any
user would, through its public API (:mod:`cpg_actor.api`, ``docs/api.md``):

* :mod:`~cpg_actor_studies.reproduction`: variants x seeds trained in parallel (locally or
  on Ray), staged evaluations, reading a results directory;
* :mod:`~cpg_actor_studies.hopper_paper`: the paper's study of the hopper: its claims and their
  verdicts, the comparisons beyond them, its figures, its report and the open-loop floor;
* :mod:`~cpg_actor_studies.sweep` (sensitivity), :mod:`~cpg_actor_studies.transfer`
  (cross-simulator), :mod:`~cpg_actor_studies.gradient` (the truncated CPG gradient),
  :mod:`~cpg_actor_studies.family` (the results folders' family of tests);
* :mod:`~cpg_actor_studies.commands`: their ``cpg-actor`` sub-commands (reproduce, sweep,
  figures, curves, gradient, transfer), which register themselves with the command line.

Nothing in ``cpg_actor`` imports this package (``tests/test_layers.py``).
"""
