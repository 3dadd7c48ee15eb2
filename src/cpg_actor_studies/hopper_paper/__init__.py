"""The paper's study of the hopper (``cpg-actor reproduce``'s report): the per-seed numbers
(:mod:`~.summary`), the paper's claims and their verdicts (:mod:`~.claims`), the comparisons
beyond them (:mod:`~.comparisons`), the paper's figures (:mod:`~.figures`), the open-loop grid
floor (:mod:`~.floor`) and ``report.md`` (:mod:`~.report`).
"""
