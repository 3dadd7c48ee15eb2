"""The public API of ``cpg_actor`` (``docs/api.md``): what a user's code, and the studies
(``cpg_actor_studies``), import from the library. Everything else is internal and may change.

    from cpg_actor.api import TrainConfig, compose_config, Runner, load_policy, evaluate_policy

Each name is imported from its module on first use (:data:`EXPORTS`), so importing this
module costs nothing and ``from cpg_actor.api import bootstrap`` loads neither torch nor a
simulator. :data:`MODULES` are namespaces whose every public name belongs to the API.
"""

from __future__ import annotations

import importlib
from typing import Any

# public name -> the module that defines it
EXPORTS: dict[str, str] = {
    # a run's configuration: composed from defaults, a preset, a file and overrides
    "TrainConfig": "cpg_actor.config",
    "compose_config": "cpg_actor.config",
    "read_config_file": "cpg_actor.config",
    "parse_override": "cpg_actor.config",
    "parse_steps": "cpg_actor.config",
    "check_seed": "cpg_actor.config",
    "check_count": "cpg_actor.config",
    "without_compile_if_no_compiler": "cpg_actor.config",
    "MAX_EPISODES": "cpg_actor.config",
    "PRESETS": "cpg_actor.config.presets",
    # a trained run's saved config, read back
    "read_config": "cpg_actor.config.saved",
    "run_robot": "cpg_actor.config.saved",
    # the robots and their tasks
    "ROBOTS": "cpg_actor.robots.registry",
    "DEFAULT_ROBOT": "cpg_actor.robots.registry",
    "get_robot": "cpg_actor.robots.registry",
    "paper_robot": "cpg_actor.robots.registry",
    "robot_of_config": "cpg_actor.robots.registry",
    "all_metrics": "cpg_actor.robots.registry",
    "all_simulators": "cpg_actor.robots.registry",
    "Robot": "cpg_actor.robots.plugin",
    "hopper_cpg": "cpg_actor.robots.hopper.cpg",  # the hopper's CPG network (HFE, KFE)
    # the agents
    "AGENTS": "cpg_actor.agents",
    "get_agent_spec": "cpg_actor.agents",
    "CPGActorAgent": "cpg_actor.agents",
    # training a run, its envs and its checkpoints
    "Runner": "cpg_actor.training.runner",
    "make_env": "cpg_actor.training.build",
    "load_checkpoint": "cpg_actor.training.checkpoint",
    "resume_checkpoint": "cpg_actor.training.checkpoint",
    # evaluating a policy
    "evaluate_policy": "cpg_actor.training.evaluation",
    "nominal_env": "cpg_actor.training.evaluation",
    # deployment
    "Policy": "cpg_actor.deploy",
    "load_policy": "cpg_actor.deploy",
    "export_policy": "cpg_actor.deploy.export",
    "read_metadata": "cpg_actor.deploy.export",
    # figures
    "save_figure": "cpg_actor.plots",
    "step_axis": "cpg_actor.plots",
    "step_labels": "cpg_actor.plots",
    "steps_text": "cpg_actor.plots",
    "metric_label": "cpg_actor.plots",
    "label": "cpg_actor.plots",
    "color": "cpg_actor.plots",
    # files and the command line
    "atomic_write_text": "cpg_actor.files",  # a file written whole or not at all
    "add_set_option": "cpg_actor.commands",  # --set KEY=VALUE, for a command a plugin adds
}
# public namespace -> its module (every public name in it is API)
MODULES: dict[str, str] = {
    "cpg": "cpg_actor.cpg",  # the Hopf CPG network (eq. 1-3), its topology and joint map
    "statistics": "cpg_actor.statistics",  # intervals, tests, claims and verdicts over seeds
    "signals": "cpg_actor.metrics.signals",  # the desired positions: smoothness, velocity, stops
    "physical": "cpg_actor.metrics.physical",  # hop apex, torque rate, power, foot slip, ...
    "robustness_verdicts": "cpg_actor.robustness.verdicts",  # the robustness suite's claims
    "inputs": "cpg_actor.inputs",  # a run's or a study's files read with one-line errors
}
__all__ = sorted([*EXPORTS, *MODULES])


def __getattr__(name: str) -> Any:
    """``name`` as its module holds it now (not kept here: a test that replaces it there,
    ``monkeypatch.setattr``, replaces it for the API's users too)."""
    if name in MODULES:
        return importlib.import_module(MODULES[name])
    if name in EXPORTS:
        return getattr(importlib.import_module(EXPORTS[name]), name)
    raise AttributeError(f"module 'cpg_actor.api' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
