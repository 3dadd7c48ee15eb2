"""The robots a run can train on: one folder per robot (its description and simulator files,
config, envs on every backend, reward, CPG presets and start gait), the env machinery they
share in ``common``, and :mod:`cpg_actor.robots.registry`, the one place a robot is named.

Importing this package (or a robot's ``plugin`` and ``config``) imports neither torch nor a
simulator: ``import cpg_actor`` registers the Gymnasium ids from here.
"""
