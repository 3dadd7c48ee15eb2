"""A run's configuration: :class:`TrainConfig` (saved as YAML next to the run), how it is
composed from defaults, presets, a config file and overrides, and the named presets
(:mod:`cpg_actor.config.presets`)."""

from cpg_actor.config.train_config import (
    MAX_EPISODES,
    MAX_SEED,
    MAX_STEPS,
    STEP_KEYS,
    TrainConfig,
    apply_dict,
    check_count,
    check_seed,
    compose_config,
    parse_override,
    parse_steps,
    read_config_file,
    without_compile_if_no_compiler,
)

__all__ = [
    "MAX_EPISODES",
    "MAX_SEED",
    "MAX_STEPS",
    "STEP_KEYS",
    "TrainConfig",
    "apply_dict",
    "check_count",
    "check_seed",
    "compose_config",
    "parse_override",
    "parse_steps",
    "read_config_file",
    "without_compile_if_no_compiler",
]
