"""The agents' tuned settings on the quadrupeds (``Robot.agent_defaults``; ANYmal B's and the
Go1's): config values, by agent, that a run on a quadruped starts from, over its recipe
(``throughput``), unless the config file or command line say otherwise
(:func:`cpg_actor.config.compose_config`). They are the settings the quadruped results were
trained with (``docs/quadruped.md``, "Training"); an agent not named here trains with the
config's defaults."""

from __future__ import annotations

from typing import Any

# one oscillator per leg (the foot-space pattern), action noise 0.1 of the joint ranges
OPEN_LOOP: dict[str, Any] = {"agent_config": {"cpg_layout": "leg", "init_std": 0.1}}

AGENT_DEFAULTS: dict[str, dict[str, Any]] = {
    # with feedback noise 0.2 (beyond the paper: the feedback is sampled)
    "cpg-actor": {"agent_config": {**OPEN_LOOP["agent_config"], "feedback_noise": 0.2}},
    "cpg-actor-open-loop": OPEN_LOOP,  # no feedback to sample
    "mlp": {"agent_config": {"init_std": 0.3}},
}
