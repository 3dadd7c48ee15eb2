"""A reproduction: variants x seeds, each an independent ``cpg-actor train`` run, in parallel.

* :mod:`~cpg_actor_studies.reproduction.plan`: settings, validation, the per-run
  ``cpg-actor train`` arguments, ``reproduce.yaml``;
* :mod:`~cpg_actor_studies.reproduction.execute`: one run (train, resume, staged evaluations)
  and the local / Ray schedulers with progress;
* :mod:`~cpg_actor_studies.reproduction.results`: reading a results directory;
* :mod:`~cpg_actor_studies.reproduction.numbers`: a run's numbers from its logged curves.
"""
