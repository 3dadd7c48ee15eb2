"""What an evaluation's traces show, by the same code for every agent and robot: the desired
joint positions' smoothness, velocity and time at a joint stop
(:mod:`~cpg_actor.metrics.signals`), and the physical metrics of the hip, joints and feet
(:mod:`~cpg_actor.metrics.physical`), which ``cpg-actor eval`` and the robustness suite show."""
