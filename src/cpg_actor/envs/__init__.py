"""The hopper's and the quadruped's environments (being moved to :mod:`cpg_actor.robots`)."""
