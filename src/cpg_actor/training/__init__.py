"""Training: the run built from its config, the loop and the hooks it calls.

* :mod:`~cpg_actor.training.runner`: PPO's loop (:class:`~cpg_actor.training.runner.Runner`);
  :mod:`~cpg_actor.training.es_runner`: the open-loop search's (CMA-ES generations);
* :mod:`~cpg_actor.training.policy`: the control step (normaliser, agent, clip, CPG state)
  that training, evaluation and deployment share;
* :mod:`~cpg_actor.training.evaluation`, :mod:`~cpg_actor.training.checkpoint`,
  :mod:`~cpg_actor.training.run_log`, :mod:`~cpg_actor.training.progress`,
  :mod:`~cpg_actor.training.episodes`, :mod:`~cpg_actor.training.run_lock`: what the loop
  evaluates, saves, logs and displays, and the one writer of a run directory.

Nothing here knows a robot: the env comes from the agent's spec, the metrics from the env.
"""
