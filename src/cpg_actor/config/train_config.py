"""`TrainConfig`: everything a training run needs, saved as YAML next to the run.

Every value can be overridden on dotted paths (``ppo.learning_rate=1e-4``, ``env.sim=pybullet``,
``agent_config.actor_hidden=[128,128]``); unknown keys are errors listing the valid ones.
"""

from __future__ import annotations

import dataclasses
import math
import re
import sys
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from cpg_actor.agents.base import AgentConfig
from cpg_actor.agents.open_loop_es import ESConfig
from cpg_actor.agents.warm_start import WarmStartConfig
from cpg_actor.device import check_device_name
from cpg_actor.files import atomic_write_text
from cpg_actor.limits import (
    MAX_ENVS,
    MAX_EPISODES,
    MAX_ROLLOUT_SAMPLES,
    MAX_SEED,
    MAX_STEPS,
    MAX_THREADS,
    MAX_YAML_BYTES,
    brief,
    check_int,
    shorten,
)
from cpg_actor.ppo.algorithm import cpp_compiler
from cpg_actor.ppo.config import PPOConfig
from cpg_actor.robots.plugin import Robot
from cpg_actor.robots.registry import DEFAULT_ROBOT, ROBOTS, get_robot
from cpg_actor.robots.spec import EnvConfig
from cpg_actor.safe_yaml import YAMLRefused, parse_yaml, yaml_error_text


def check_seed(seed: Any, name: str = "--seed") -> None:
    """ValueError unless ``seed`` is an integer from 0 to :data:`MAX_SEED`."""
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= MAX_SEED:
        raise ValueError(
            f"{name} must be an integer from 0 to 2**63-1 ({MAX_SEED}), got {brief(seed)}"
        )


def check_count(value: Any, name: str, high: int) -> None:
    """ValueError unless ``value`` is an integer from 1 to ``high``."""
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= high:
        raise ValueError(f"{name} must be an integer from 1 to {high:,}, got {brief(value)}")


def _default_env_config() -> EnvConfig:
    return get_robot(DEFAULT_ROBOT).config_class()


def check_cpg_choice(agent_config: AgentConfig, robot: Robot) -> None:
    """ValueError unless ``agent_config.cpg_layout`` and ``cpg_gait`` are empty or among
    ``robot``'s CPG layouts and that layout's gaits."""
    layouts = robot.cpg_layouts()
    layout = agent_config.cpg_layout
    if layout and layout not in layouts:
        raise ValueError(
            f"agent_config.cpg_layout must be one of {', '.join(layouts)} on robot "
            f"{brief(robot.name)} (or empty), got {brief(layout)}"
        )
    gait, gaits = agent_config.cpg_gait, layouts[layout or next(iter(layouts))].gaits
    if gait and not gaits:
        raise ValueError(
            f"agent_config.cpg_gait: the CPG of robot {robot.name!r} has no gaits; leave it empty"
        )
    if gait and gait not in gaits:
        raise ValueError(
            f"agent_config.cpg_gait must be one of {', '.join(gaits)} (or empty), got {brief(gait)}"
        )


@dataclass
class TrainConfig:
    """One training run. ``total_steps`` counts control steps summed over all environments."""

    agent: str = "cpg-actor"  # a name in cpg_actor.agents.AGENTS
    robot: str = DEFAULT_ROBOT  # a name in cpg_actor.robots.registry.ROBOTS; env holds its config
    preset: str = "paper"  # the preset the run started from (cpg_actor.config.presets.PRESETS)
    seed: int = 0
    num_envs: int = 16  # x ppo.num_steps = 2,048 samples per update, as Baselines' ppo2
    total_steps: int = 500_000  # the quick start
    # env steps spent before this run finding its start (the start gait's search, see
    # agent_config.start_gait), counted in total_steps: the run trains total_steps -
    # search_steps and its step counter starts at search_steps (cpg-actor reproduce
    # --count-search-steps sets it); 0: the run's own steps only
    search_steps: int = 0
    checkpoint_interval: int = 50  # iterations between checkpoints (and one at the end)
    # deterministic evaluation during training: every eval_interval iterations (0: never),
    # one episode on each of eval_episodes envs of its own (cpg_actor.training.evaluation)
    eval_interval: int = 10
    eval_episodes: int = 5
    log_interval: int = 1  # iterations between TensorBoard / metrics.csv rows
    histogram_interval: int = 10  # iterations between parameter histograms
    torch_threads: int = 1  # torch intra-op threads (the simulator uses the other cores)
    # torch threads during the PPO update, when the simulator is idle; None: every usable core
    # for minibatches of at least 1,024 samples (the throughput preset), else torch_threads
    update_threads: int | None = None
    device: str = "cpu"  # networks, storage and PPO: cpu | cuda | cuda:N | auto (cpg_actor.device)
    env_threads: int | None = None  # simulator threads, None: the env's default
    agent_config: AgentConfig = field(default_factory=AgentConfig)
    ppo: PPOConfig = field(default_factory=PPOConfig)
    warm_start: WarmStartConfig = field(default_factory=WarmStartConfig)  # cho2019-warm only
    # the robot's env config (its Robot.config_class: HopperConfig, QuadrupedConfig, ...)
    env: EnvConfig = field(default_factory=_default_env_config)
    es: ESConfig = field(default_factory=ESConfig)  # open-loop-es only: the CMA-ES search

    @property
    def steps_per_iteration(self) -> int:
        return self.num_envs * self.ppo.num_steps

    @property
    def num_iterations(self) -> int:
        return max(1, math.ceil((self.total_steps - self.search_steps) / self.steps_per_iteration))

    def validate(self) -> None:
        from cpg_actor.agents import get_agent_spec

        get_agent_spec(self.agent)
        from cpg_actor.config.presets import check_preset

        check_preset(self.preset)
        # every count bounded (cpg_actor.limits), before anything is built
        check_int(self.eval_interval, "eval_interval (0: no evaluation during training)", 0,
                  MAX_STEPS)  # fmt: skip
        for name, high in (
            ("num_envs", MAX_ENVS),
            ("total_steps", MAX_STEPS),
            ("checkpoint_interval", MAX_STEPS),  # iterations: a run has fewer than steps
            ("log_interval", MAX_STEPS),
            ("histogram_interval", MAX_STEPS),
            ("torch_threads", MAX_THREADS),
            ("eval_episodes", MAX_EPISODES),
        ):
            check_int(getattr(self, name), name, 1, high)
        steps = self.search_steps
        check_int(steps, "search_steps", 0, MAX_STEPS)
        if steps >= self.total_steps:
            raise ValueError(
                f"search_steps ({steps:,}) must be below total_steps ({self.total_steps:,}): "
                "the start gait's search would use the whole budget"
            )
        check_seed(self.seed, "seed")
        for name in ("update_threads", "env_threads"):
            if getattr(self, name) is not None:
                check_int(getattr(self, name), f"{name} (or null: automatic)", 1, MAX_THREADS)
        if getattr(self.env, "normalized_actions", False):
            raise ValueError(
                "env.normalized_actions is for off-the-shelf RL libraries (gymnasium.make); "
                "the project's agents act on desired positions in rad: leave it false"
            )
        from cpg_actor.robots.registry import robot_of_config

        robot = get_robot(self.robot)
        try:
            holds = robot_of_config(self.env).name
        except ValueError:  # a config of the caller's own env (a test double, an extension)
            holds = self.robot
        if holds != self.robot:
            raise ValueError(
                f"env holds the config of robot {brief(holds)}, not of {brief(self.robot)}"
            )
        from cpg_actor.agents import AGENTS

        spec = AGENTS[self.agent]
        if spec.robots is not None and self.robot not in spec.robots:
            usable = sorted(
                name for name, other in AGENTS.items()
                if other.robots is None or self.robot in other.robots
            )  # fmt: skip
            raise ValueError(
                f"agent {brief(self.agent)} is built for {', '.join(spec.robots)} only; on robot "
                f"{brief(self.robot)} use one of {', '.join(usable)}"
            )
        if getattr(self.env, "privileged_observation", False) and not spec.privileged_critic:
            takers = sorted(name for name, other in AGENTS.items() if other.privileged_critic)
            raise ValueError(
                f"env.privileged_observation: agent {brief(self.agent)} has no privileged "
                f"critic (its actor would read those entries); agents that have one: "
                f"{', '.join(takers)}; or set it false"
            )
        if self.agent_config.observation_scales and not spec.observation_scales:
            takers = sorted(name for name, other in AGENTS.items() if other.observation_scales)
            raise ValueError(
                f"agent_config.observation_scales: agent {brief(self.agent)} does not scale "
                f"its observation; agents that do: {', '.join(takers)}; or leave it empty"
            )
        check_device_name(self.device)
        self.agent_config.validate()
        check_cpg_choice(self.agent_config, robot)
        self.ppo.validate()
        self.warm_start.validate()
        if self.steps_per_iteration > MAX_ROLLOUT_SAMPLES:
            raise ValueError(
                f"num_envs x ppo.num_steps ({self.num_envs:,} x {self.ppo.num_steps:,}) is a "
                f"rollout of {self.steps_per_iteration:,} samples, above the "
                f"{MAX_ROLLOUT_SAMPLES:,} accepted; use fewer envs or steps"
            )
        if self.num_envs * self.warm_start.rollout_steps > MAX_ROLLOUT_SAMPLES:
            raise ValueError(
                f"num_envs x warm_start.rollout_steps ({self.num_envs:,} x "
                f"{self.warm_start.rollout_steps:,}) is above the {MAX_ROLLOUT_SAMPLES:,} "
                "samples accepted; use fewer envs or steps"
            )
        if self.steps_per_iteration < self.ppo.num_minibatches:
            raise ValueError("num_envs * ppo.num_steps must be >= ppo.num_minibatches")
        self.es.validate()

    # -- (de)serialisation -------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        return _to_plain(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TrainConfig:
        """A saved config (a run's ``config.yaml``, a checkpoint's). One saved before a field
        existed keeps what it trained with: the drives coasting past v_max (``env.actuator_law``
        "coast"), the update on ``torch_threads`` (``update_threads``) and a quadruped's every
        geom touching the floor (``env.floor_contacts`` "all")."""
        data = dict(data)
        env = data.get("env")
        if isinstance(env, dict) and "actuator_law" not in env:
            data["env"] = {**env, "actuator_law": "coast"}
        if isinstance(env, dict) and "floor_contacts" not in env and _has_floor_contacts(data):
            data["env"] = {**data["env"], "floor_contacts": "all"}  # every geom, as before
        if "update_threads" not in data and "torch_threads" in data:
            data["update_threads"] = data["torch_threads"]
        config = cls()
        apply_dict(config, data, prefix="")
        return config

    def save(self, path: Path) -> None:
        atomic_write_text(yaml.safe_dump(self.to_dict(), sort_keys=False), Path(path))

    @classmethod
    def load(cls, path: Path) -> TrainConfig:
        """A run's saved config; ValueError for a file that holds none (an emptied
        config.yaml would otherwise read as every default)."""
        data = read_config_file(path)
        if not data:
            raise ValueError(f"{path} holds no config keys; a run's config.yaml holds those "
                             "cpg-actor train wrote (damaged or emptied?)")  # fmt: skip
        return cls.from_dict(data)


def _has_floor_contacts(data: dict[str, Any]) -> bool:
    """The saved config's robot has ``env.floor_contacts`` (the quadrupeds)."""
    from cpg_actor.robots.registry import ROBOTS, get_robot

    robot = data.get("robot", TrainConfig.robot)
    if robot not in ROBOTS:
        return False  # the config's validation names it
    fields = dataclasses.fields(get_robot(robot).config_class)
    return any(field.name == "floor_contacts" for field in fields)


def compose_config(
    preset: str | None = None,
    config_file: str | Path | None = None,
    values: dict[str, Any] | None = None,
    overrides: typing.Iterable[str] = (),
) -> TrainConfig:
    """The one place a run's config is put together, in this order (later wins): the
    defaults, the agent's defaults on the robot (its tuned settings there,
    :attr:`cpg_actor.robots.plugin.Robot.agent_defaults`), the recipe (``preset``, else the
    config file's, else the robot's, :attr:`~cpg_actor.robots.plugin.Robot.recipe`), the YAML
    ``config_file``, ``values`` (a nested mapping: the command-line flags), then each
    ``KEY=VALUE`` of ``overrides`` (``--set``). Validated; a clear ValueError (or
    FileNotFoundError) names what is wrong."""
    from cpg_actor.agents import get_agent_spec
    from cpg_actor.config.presets import preset_values

    file_data: dict[str, Any] = {}
    if config_file is not None:
        path = Path(config_file)
        if path.is_dir():
            raise ValueError(
                f"--config {path} is a directory; give a YAML file (e.g. a run's config.yaml)"
            )
        if not path.is_file():
            raise FileNotFoundError(f"config file {path} does not exist")
        file_data = read_config_file(path)
    chosen = preset or file_data.get("preset")
    given = [dict(values or {}), *(parse_override(text) for text in overrides)]

    def compose(
        agent_defaults: Mapping[str, Any],
        recipe: str,
        robot: str | None = None,
        layers: list[dict[str, Any]] = given,
    ) -> TrainConfig:
        config = TrainConfig()
        if robot is not None:  # first: the recipe's env values are then the robot's
            apply_dict(config, {"robot": robot}, prefix="")
        apply_dict(config, dict(agent_defaults), prefix="")
        env_class = None if robot is None else type(config.env)  # the robot's env values
        apply_dict(config, preset_values(recipe, env_class), prefix="")
        apply_dict(config, file_data, prefix="")
        config.preset = recipe
        for layer in layers:
            apply_dict(config, layer, prefix="")
        return config

    # which agent and robot (no recipe names one but the old "anymal"): from the flags and --set
    # only those two keys, since the others can be the robot's env keys, in any order; then the
    # robot's recipe, unless one is named, and its defaults for the agent
    choice = [{key: layer[key] for key in ("agent", "robot") if key in layer} for layer in given]
    config = compose({}, chosen or TrainConfig.preset, layers=choice)
    get_agent_spec(config.agent)  # an unknown agent: its ValueError now
    robot = ROBOTS.get(config.robot)  # an unknown robot: validate() says so
    if robot is not None:
        config = compose(
            robot.agent_defaults.get(config.agent, {}), chosen or robot.recipe, config.robot
        )
    config.validate()
    return config


def without_compile_if_no_compiler(config: TrainConfig) -> TrainConfig:
    """``ppo.compile`` off, with a note, where no C++ compiler is installed."""
    if config.ppo.compile and cpp_compiler() is None:
        print(
            "note: no C++ compiler found (g++, c++, clang++), so ppo.compile is off: the same "
            "training with slower updates; install one (e.g. apt install g++) to compile",
            file=sys.stderr,
        )
        config.ppo.compile = False
    return config


def read_config_file(path: Path) -> dict[str, Any]:
    """The mapping of config keys in a YAML file; a clear ValueError if it is not one (read by
    :mod:`cpg_actor.safe_yaml`: bounded in size, aliases and depth, each key once)."""
    if Path(path).is_file() and Path(path).stat().st_size > MAX_YAML_BYTES:
        raise ValueError(
            f"{path} has {Path(path).stat().st_size:,} bytes, above the {MAX_YAML_BYTES:,} "
            "accepted for a config file (a run's config.yaml has a few KB)"
        )
    try:
        data = parse_yaml(Path(path).read_text(encoding="utf-8")) or {}
    except UnicodeDecodeError as error:  # a binary file: a checkpoint, an image, ...
        raise ValueError(
            f"{path} is not a YAML text file (byte {error.start} is not UTF-8 text); give a "
            "YAML file of config keys, e.g. a run's config.yaml"
        ) from None
    except YAMLRefused as error:
        raise ValueError(f"{path} is refused: the YAML {error}") from None
    except yaml.YAMLError as error:  # in one line: the problem and where
        raise ValueError(f"{path} is not valid YAML{yaml_error_text(error)}") from None
    except ValueError as error:  # an integer of too many digits, ...
        raise ValueError(f"{path} is not valid YAML: {shorten(str(error))}") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path} must hold a mapping of config keys")
    return data


def _to_plain(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _to_plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, (tuple, list)):
        return [_to_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _to_plain(v) for k, v in value.items()}
    return value


def _field_types(obj: Any) -> dict[str, Any]:
    try:
        return typing.get_type_hints(type(obj))
    except Exception:  # a type hint that cannot be resolved: fall back to the current values
        return {f.name: type(getattr(obj, f.name)) for f in dataclasses.fields(obj)}


_YAML11_FLOAT = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)[eE][-+]?\d+")


def _coerce(value: Any, annotation: Any, key: str) -> Any:
    """Convert a YAML value to the field's annotated type, or raise a clear ValueError."""
    origin = typing.get_origin(annotation)
    args = typing.get_args(annotation)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        errors = []
        for arg in args:
            if arg is type(None):
                continue
            try:
                return _coerce(value, arg, key)
            except ValueError as error:
                errors.append(str(error))
        raise ValueError(errors[0] if errors else f"{key}: invalid value {brief(value)}")
    if annotation is Any:
        return value
    if annotation is bool:
        if isinstance(value, bool):
            return value
        raise ValueError(f"{key} must be true or false, got {brief(value)}")
    if annotation is int:  # (an infinite float, 1e309, has no integer: one line, no overflow)
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or (isinstance(value, float) and not value.is_integer())
        ):
            raise ValueError(f"{key} must be an integer, got {brief(value)}")
        return int(value)
    if annotation is float:
        if isinstance(value, str) and _YAML11_FLOAT.fullmatch(value.strip()):
            return float(value)  # YAML 1.1 reads 1e-4 (no dot) as a string
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{key} must be a number, got {brief(value)}")
        return float(value)
    if annotation is str:
        if not isinstance(value, str):
            raise ValueError(f"{key} must be a string, got {brief(value)}")
        return value
    if origin in (tuple, list) or annotation in (tuple, list):
        if not isinstance(value, (list, tuple)):
            raise ValueError(f"{key} must be a list, got {brief(value)}")
        item = args[0] if args else Any
        items = [_coerce(v, item, f"{key}[{i}]") for i, v in enumerate(value)]
        return tuple(items) if (origin or annotation) is tuple else items
    if origin is dict or annotation is dict:
        if not isinstance(value, dict):
            raise ValueError(f"{key} must be a mapping, got {brief(value)}")
        return value
    return value


def apply_dict(obj: Any, data: dict[str, Any], prefix: str) -> None:
    """Set fields of the dataclass ``obj`` from a nested mapping, validating keys and types.
    A ``robot`` key of a ``TrainConfig`` comes first: it swaps ``env`` for that robot's
    default config when ``env`` holds another robot's."""
    if prefix == "" and isinstance(obj, TrainConfig) and "robot" in data:
        config_class = get_robot(str(data["robot"])).config_class
        obj.robot = str(data["robot"])
        if type(obj.env) is not config_class:  # a subclass is another robot's config
            obj.env = config_class()
        data = {key: value for key, value in data.items() if key != "robot"}
    names = {f.name: f for f in dataclasses.fields(obj)}
    hints = _field_types(obj)
    for key, value in data.items():
        path = f"{prefix}{key}"
        if key not in names:
            raise ValueError(
                f"unknown config key '{shorten(path)}'; valid keys here: {', '.join(sorted(names))}"
            )
        current = getattr(obj, key)
        if dataclasses.is_dataclass(current):
            if not isinstance(value, dict):
                raise ValueError(f"'{path}' is a section; give a mapping of its keys")
            if hasattr(type(current), "from_dict") and prefix == "" and key == "env":
                merged = {**_to_plain(current), **value}
                for name, section in value.items():  # a section of it (the perturbation):
                    inner = getattr(current, name, None)  # the keys given, the others kept
                    if dataclasses.is_dataclass(inner) and isinstance(section, dict):
                        merged[name] = {**_to_plain(inner), **section}
                try:
                    setattr(obj, key, type(current).from_dict(merged))
                except (TypeError, ValueError) as error:
                    raise ValueError(f"invalid env config: {error}") from None
            else:
                apply_dict(current, value, prefix=f"{path}.")
        elif key in STEP_KEYS and isinstance(value, str):  # "500k" as in --total-steps
            setattr(obj, key, parse_steps(value))
        else:
            setattr(obj, key, _coerce(value, hints.get(key, Any), path))


_ASSIGNMENT = re.compile(r"^([A-Za-z_][\w.]*)=(.*)$", re.DOTALL)


def parse_override(text: str) -> dict[str, Any]:
    """``"ppo.learning_rate=1e-4"`` -> ``{"ppo": {"learning_rate": 1e-4}}`` (value read as YAML)."""
    match = _ASSIGNMENT.match(text.strip())
    if not match:
        raise ValueError(f"--set expects KEY=VALUE with a dotted key, got {brief(text)}")
    key, raw = match.groups()
    try:
        value = parse_yaml(raw) if raw.strip() else None
    except yaml.YAMLError:
        value = raw
    except YAMLRefused as error:  # too large, too deep: refused, not read as a string
        raise ValueError(f"--set {shorten(key)}: the YAML value {error}") from None
    except ValueError as error:  # an integer of too many digits, ...
        raise ValueError(f"--set {shorten(key)}: {shorten(str(error))}") from None
    if isinstance(value, str) and re.fullmatch(r"[-+]?\d*\.?\d+[eE][-+]?\d+", value):
        value = float(value)  # YAML 1.1 reads 1e-4 as a string
    nested: dict[str, Any] = {}
    node = nested
    parts = key.split(".")
    for part in parts[:-1]:
        node = node.setdefault(part, {})
    node[parts[-1]] = value
    return nested


# step counts a config file or --set may also write with a suffix (500k, 20M)
STEP_KEYS = ("total_steps",)
_SUFFIXES = {"k": 1_000, "m": 1_000_000, "g": 1_000_000_000, "b": 1_000_000_000}


def parse_steps(text: str | int) -> int:
    """``"20M"`` -> 20_000_000, ``"500k"`` -> 500_000, ``"1e6"`` -> 1_000_000; must be > 0."""
    raw = str(text).strip().lower().replace("_", "")
    try:
        if raw and raw[-1] in _SUFFIXES:
            value = float(raw[:-1]) * _SUFFIXES[raw[-1]]
        else:
            value = float(raw)
    except ValueError:
        raise ValueError(
            f"invalid step count {brief(text)}; use e.g. 300000, 500k or 20M"
        ) from None
    if not math.isfinite(value) or value != int(value) or value <= 0:
        raise ValueError(f"the step count must be a positive integer, got {brief(text)}")
    if value > MAX_STEPS:
        raise ValueError(
            f"the step count {brief(text)} is above the largest accepted, {MAX_STEPS:.0e} "
            "(years of training on any machine)"
        )
    return int(value)
