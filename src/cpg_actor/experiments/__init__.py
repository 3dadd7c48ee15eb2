"""Reproduction of the paper's comparison: variants x seeds, in parallel, figures and a report.

* :mod:`~cpg_actor.experiments.plan`: settings, validation, the per-run ``cpg-actor train``
  arguments, ``reproduce.yaml``;
* :mod:`~cpg_actor.experiments.execute`: one run (train, resume, staged evaluations) and the
  local / Ray schedulers with progress;
* :mod:`~cpg_actor.experiments.metrics`: final return, smoothness, velocity share, bootstrap
  confidence intervals, the tests (Welch, Holm) behind the claim verdicts;
* :mod:`~cpg_actor.experiments.results`: reading a results directory;
* :mod:`~cpg_actor.experiments.figures` and :mod:`~cpg_actor.experiments.report`: the paper's
  figures and ``report.md``.
"""
