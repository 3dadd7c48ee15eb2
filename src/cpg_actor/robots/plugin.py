"""What a robot plug-in gives the project: a :class:`Robot`, one entry of
:data:`cpg_actor.robots.registry.ROBOTS`.

Each robot's folder defines its entry in ``plugin.py``. The entry is light to import (no torch,
no simulator): what needs them (the env, the CPG presets, the simulator files) is a function
that imports on call.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any


def load(path: str) -> Any:
    """The object at ``path``, "module:name" (as a Gymnasium entry point), imported now."""
    module, _, name = path.partition(":")
    return getattr(importlib.import_module(module), name)


@dataclass(frozen=True)
class MetricInfo:
    """How an env's episode metric (``info["episode_metrics"]``) reads on a figure or in a
    printed line."""

    label: str  # plain words
    unit: str = ""  # "" for a ratio or a count
    undefined: str = ""  # when an episode leaves it NaN (undefined), in words
    short: str = ""  # its name in a table's column (empty: the label)

    @property
    def column(self) -> str:
        """Its column heading: the short name and the unit."""
        name = self.short or self.label
        return f"{name} ({self.unit})" if self.unit else name


@dataclass(frozen=True)
class GymId:
    """A Gymnasium id: ``gymnasium.make`` builds ``entry_point``, ``gymnasium.make_vec`` the
    ``vector_entry_point`` (both "module:Class", imported only then)."""

    id: str
    entry_point: str
    vector_entry_point: str
    kwargs: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class CPGLayout:
    """How a robot's CPG drives its joints (``agent_config.cpg_layout``).

    ``preset(dt, initial=..., check_inputs=..., dtype=...)`` builds the CPG (with ``gait=``
    where ``gaits`` names any, with ``bounds=`` where it accepts them). Its oscillators drive
    the joints through a joint map (``joints``: the joint, by index in the robot's joint
    order, that each oscillator drives; None: one oscillator per joint, in order; the joints
    no oscillator drives are held at the nominal pose), or through ``pattern``, a module built
    from the nominal pose that maps the oscillators' phase and amplitude to every joint.
    ``gaits``: the gaits it can start in (``agent_config.cpg_gait``'s choices; the first is the
    default), each with its footfall pattern: every leg's phase, a fraction of a cycle, in the
    robot's leg order. ``planar_drive``: where the layout steps in the ground plane, a builder
    of the module mapping the velocity command (B, 3) to each oscillator's drive and step
    direction (B, N) each, which the pattern takes as a third argument
    (``agent_config.cpg_planar_steps``).
    """

    preset: Callable[..., Any]
    joints: tuple[int, ...] | None = None
    pattern: Callable[[Sequence[float]], Any] | None = None
    gaits: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    planar_drive: Callable[[], Any] | None = None


@dataclass(frozen=True)
class Paper:
    """What the paper's reproduction (``cpg-actor reproduce``: its report and its open-loop
    floor) needs of the robot it studies (``Robot.paper`` names it, "module:NAME")."""

    reward_terms: tuple[str, ...]  # eq. 4's terms, as its envs log them (reward_terms/NAME)
    # (env config, grid or None: the default) -> the open-loop grid floor: the best constant
    # CPG parameters by episode return and by hop height (cpg_actor_studies.hopper_paper.floor)
    open_loop_floor: Callable[[Any, dict | None], dict[str, Any]]
    # (joint names of traces saved without their action bounds, None where they name none) ->
    # those joints' (low, high) limits (rad), None where the traces are not this robot's
    joint_limits: Callable[[tuple[str, ...] | None], tuple[Any, Any] | None]


@dataclass(frozen=True)
class Robot:
    """One robot, as the trainer, the CLI, evaluation and export see it."""

    name: str  # TrainConfig.robot and `--robot`
    model: str  # the RobotSpec.name of its envs (the exported policy's robot_model)
    config_class: type  # its env config dataclass (with from_dict): TrainConfig.env
    make: Callable[..., Any]  # (num_envs, config, num_threads) -> its vector env
    # agent_config.cpg_layout -> its CPG layout (the first is the default), built on call
    cpg_layouts: Callable[[], dict[str, CPGLayout]]
    metrics: dict[str, MetricInfo]  # its envs' episode metrics, the headline first
    gym_ids: tuple[GymId, ...]
    # for a policy deployed outside the project (cpg_actor.deploy.export): the MJCF of the model
    # its MuJoCo env simulates under a config, and where each entry of the actor's observation
    # comes from in that model's data under a config (one mapping per entry, the critic's
    # privileged entries left out; cpg_actor.deploy.export.OBSERVATION_SOURCES)
    mjcf: Callable[[Any], str]
    observation_sources: Callable[[Any], tuple[dict[str, Any], ...]]
    # each shipped simulator file and the text its description generates
    # (`python -m cpg_actor.robots` rewrites them)
    assets: Callable[[], dict[Path, str]]
    start_gait: Path | None = None  # the gait of agent_config.start_gait "search", if shipped
    # the simulators its envs run on (`--sim`), the first the default; with more than one,
    # its env config's ``sim`` field names the run's
    simulators: tuple[str, ...] = ("mujoco",)
    # the agents' tuned settings on it, by agent name: config values (a nested mapping, as a
    # recipe's) a run of that agent starts from unless its recipe, config file or command line
    # say otherwise (cpg_actor.config.compose_config)
    agent_defaults: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    # the recipe (cpg_actor.config.presets.PRESETS) a run on it follows when neither
    # ``--preset`` nor its config file names one: with ``agent_defaults``, its tuned settings
    recipe: str = "paper"
    # the `cpg-actor` commands it brings (listed after the generic ones): command name ->
    # (its module, with HELP, add_arguments and run; the module's HELP)
    commands: Mapping[str, tuple[str, str]] = field(default_factory=dict)
    # the agents built for it alone: "module:NAME" of each one's AgentSpec
    # (cpg_actor.agents.AGENTS lists them, imported on first use)
    agents: tuple[str, ...] = ()
    # "module:NAME" of its Paper, where the paper's reproduction studies it (the hopper)
    paper: str | None = None

    @property
    def episode_steps(self) -> int:
        """Control steps of an episode under the default config."""
        return int(self.config_class().episode_steps)

    @property
    def headline_metric(self) -> str:
        """The episode metric that says how well a run did (the first of ``metrics``)."""
        return next(iter(self.metrics))

    @property
    def perturbations(self) -> Any:
        """The perturbations the robustness suite runs on this robot: its env config's
        ``perturbation_table()`` (a
        :class:`~cpg_actor.robots.common.perturbation.PerturbationTable`); None where the
        config declares none."""
        table = getattr(self.config_class, "perturbation_table", None)
        return None if table is None else table()

    def cpg_layout(self, layout: str = "") -> tuple[str, CPGLayout]:
        """The name and the :class:`CPGLayout` of its CPG layout ``layout`` (empty: its
        default, the first); ValueError naming its layouts if it has none of that name."""
        layouts = self.cpg_layouts()
        name = layout or next(iter(layouts))
        if name not in layouts:
            raise ValueError(
                f"agent_config.cpg_layout {name!r}: robot '{self.name}' has the CPG layouts "
                f"{', '.join(layouts)}"
            )
        return name, layouts[name]

    def paper_parts(self) -> Paper:
        """Its :class:`Paper` (imported now); ValueError if the paper does not study it."""
        if not self.paper:
            raise ValueError(f"the paper's reproduction does not study the {self.name}")
        return load(self.paper)

    def simulator(self, config: Any) -> str:
        """The simulator an env config of this robot runs on."""
        return str(config.sim) if len(self.simulators) > 1 else self.simulators[0]

    def simulator_config(self, sim: str) -> dict[str, Any]:
        """The env config values that choose simulator ``sim``; ValueError if it has none."""
        if sim not in self.simulators:
            raise ValueError(f"--sim {sim}: the {self.name} runs on {', '.join(self.simulators)}")
        return {"sim": sim} if len(self.simulators) > 1 else {}
