"""The agents' tuned settings on the hopper (``Robot.agent_defaults``): config values, by agent,
that a run on the hopper starts from unless its preset, config file or command line say
otherwise (:func:`cpg_actor.config.compose_config`). Each was chosen by tuning
(``docs/results/tuning``); an agent not named here trains with the config's defaults."""

from __future__ import annotations

from typing import Any

# The CPG-Actor at its best: the start gait of the open-loop search, the command inside the
# joint range, Gaussian noise on the joint command of 0.3 half-ranges whose std never falls
# below a tenth of that, with the gradient through 8 CPG steps. (cpg-actor-paper is the
# paper's method: its preset start, position noise of 1 half-range, the one-step gradient; it
# has no tuned settings.)
CPG_ACTOR: dict[str, Any] = {
    "agent_config": {
        "start_gait": "search",
        "output_bound": True,
        "exploration": "position",
        "init_std": 0.3,
        "action_std_floor": 0.1,
    },
    "ppo": {"bptt_steps": 8},
}

AGENT_DEFAULTS: dict[str, dict[str, Any]] = {
    # with the same floor under its std as the CPG-Actor's, which won on its tuning seeds too
    "mlp": {
        "agent_config": {"init_std": 0.3, "action_std_floor": 0.1},
        "ppo": {"learning_rate": 1e-3},
    },
    # the warm start's noise (warm_start.action_noise) and init_std
    "mlp-warm": {
        "agent_config": {"start_gait": "search", "init_std": 0.3},
        "warm_start": {"action_noise": 0.1},
    },
    "cpg-actor": CPG_ACTOR,
    # the CPG-Actor's settings without its feedback (not tuned on its own): what PPO adds to
    # the searched open loop
    "cpg-actor-open-loop": CPG_ACTOR,
    "cho2019-warm": {
        "agent_config": {"start_gait": "search"},
        "warm_start": {"action_noise": 0.05},
        "ppo": {"learning_rate": 1e-3},  # the best of its tuning
    },
    "cho2019-paper": {"agent_config": {"init_std": 0.3}},
    # inside the CPG-Actor's output bound, so that the gait it finds is a start it accepts
    "open-loop-es": {"agent_config": {"output_bound": True}},
}
