"""What a reproduction runs: settings, validation, per-run training arguments, ``reproduce.yaml``.

Every (variant, seed) is an independent ``cpg-actor train`` run in ``OUT/runs/VARIANT/seedS``.
The settings that decide the results (``IDENTITY_KEYS``) are saved in ``OUT/reproduce.yaml``;
re-running with the same ones resumes, with more variants or seeds extends the reproduction
(its finished runs are kept), with other changes is refused unless ``--overwrite``.
How the runs are executed (workers, Ray address) may change between invocations.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import yaml

from cpg_actor.api import MAX_EPISODES, atomic_write_text
from cpg_actor.files import MARKER, RESULTS, clear_project_dir, refuse_linked_folders, write_marker
from cpg_actor.limits import MAX_ENVS, MAX_SEEDS, brief, check_int
from cpg_actor.machine import usable_cores
from cpg_actor.safe_yaml import read_yaml

# the paper's progressive-hopping figure: 1M, 20M and 60M of 60M steps
STAGE_FRACTIONS: tuple[float, ...] = (1 / 60, 1 / 3, 1.0)
STAGE_LABELS: tuple[str, ...] = ("1/60", "1/3", "1")
# about this many checkpoints per run, so one lies near each stage and Fig. 5 has a history
TARGET_CHECKPOINTS = 240
SETTINGS_FILE = "reproduce.yaml"
IDENTITY_KEYS = (
    "variants",
    "seeds",
    "total_steps",
    "num_envs",
    "sim",
    "overrides",
    "eval_episodes",
    "stage_fractions",
)


HOPPER_RANDOMIZE = (
    "env.randomize.payload=[0,1.02]",
    "env.randomize.friction=[0.4,1.2]",
    "env.randomize.latency=[0,1]",
    "env.randomize.obs_noise=[0,1]",
    "env.randomize.motor_strength=[0.8,1.2]",
)

FIELD_MLP = (
    "agent_config.actor_hidden=[512,256,128]",
    "agent_config.critic_hidden=[512,256,128]",
    "agent_config.activation=elu",
    "ppo.entropy_coef=0.01",
    "ppo.value_loss_coef=1.0",
    "ppo.max_grad_norm=1.0",
)
FIELD_MLP_TUNED = (*FIELD_MLP, "env.tracking_sigma=0.25")  # the recipe with its tuning's choice

# Variants that are an agent with settings of their own: name -> (agent, --set overrides).
# Their settings come before the reproduction's own --set, which can still change them. The
# paper's CPG-Actor (cpg-actor-paper) with one change each, against which they are compared.
VARIANTS: dict[str, tuple[str, tuple[str, ...]]] = {
    # the paper's feedback: the MLP's linear output is xi (rad/s) and kappa (rad/s^2)
    "cpg-actor-unbounded": (
        "cpg-actor-paper",
        (
            "agent_config.feedback_tanh=false",
            "agent_config.xi_scale=1.0",
            "agent_config.kappa_scale=1.0",
        ),
    ),
    # the hop-height reward: r1 paid once per flight, at its apex (env.hop_reward=apex)
    "cpg-actor-apex": ("cpg-actor-paper", ("env.hop_reward=apex",)),
    "mlp-apex": ("mlp", ("env.hop_reward=apex",)),
    # beyond the paper's one-step gradient (docs/training.md): k = 32 chosen by tuning, on
    # seeds that are never reported
    "cpg-actor-bptt32": ("cpg-actor-paper", ("ppo.bptt_steps=32",)),
    "cpg-actor-feedback-noise": ("cpg-actor-paper", ("agent_config.feedback_noise=0.1",)),
    # the CPG's own learning rate falling with the schedule's (presets that set one)
    "cpg-actor-follow": ("cpg-actor", ("ppo.cpg_lr_schedule=follow",)),
    # the action noise's std without its floor (cpg-actor's and mlp's default, chosen on
    # tuning seeds) and with one for Cho et al. (agent_config.action_std_floor; it lost there)
    "cpg-actor-no-floor": ("cpg-actor", ("agent_config.action_std_floor=0",)),
    "mlp-no-floor": ("mlp", ("agent_config.action_std_floor=0",)),
    "cho2019-warm-floor": ("cho2019-warm", ("agent_config.action_std_floor=0.1",)),
    # the field's MLP recipe on the quadrupeds (legged_gym / rsl_rl, Rudin et al. 2021): actor
    # and critic of 512-256-128 ELU units, entropy bonus 0.01, value-loss weight and gradient
    # norm 1; the rest of rsl_rl's PPO (5 epochs x 4 minibatches, learning rate 1e-3 adapted
    # to KL 0.01, gamma 0.99, lambda 0.95, clip 0.2) is the throughput recipe's, and the MLP's
    # init_std 0.3 of the Go1's joint half-ranges is 0.18-0.27 rad (rsl_rl: 1.0 x 0.25 rad);
    # legged_gym's tracking kernel 0.25, chosen by its tuning on the omnidirectional task
    "mlp-field": ("mlp", FIELD_MLP_TUNED),
    # the same MLP cloned from the trot the quadrupeds' CPG-Actor starts from (its foot-space
    # layout), with the MLP's quadruped noise (0.3; mlp-warm's config default is 1.0) and
    # mlp-field's tracking kernel, from which its tuning started
    "mlp-warm-field": (
        "mlp-warm",
        (*FIELD_MLP_TUNED, "agent_config.cpg_layout=leg", "agent_config.init_std=0.3"),
    ),
    # randomised training with the hopper's ranges (docs/robustness.md; the payload is in kg)
    "cpg-actor-randomized": ("cpg-actor", HOPPER_RANDOMIZE),
    "mlp-randomized": ("mlp", HOPPER_RANDOMIZE),
    # MuJoCo Playground's Go1 joystick recipe as its source runs it, env and PPO alike: its
    # recipe (VARIANT_RECIPES) holds every setting (docs/go1.md, "MuJoCo Playground's recipe").
    # mlp-field, beside it, is the field's network and PPO weights on this project's task
    "mlp-playground": ("mlp", ()),
    # legged_gym's ANYmal B recipe as its source runs it (rsl_rl v1.0.2), env and PPO alike,
    # on flat ground (docs/quadruped.md, "legged_gym's recipe"); --set robot=anymal
    "mlp-legged-gym": ("mlp", ()),
}

# Variants that are a recipe of their own (cpg-actor train --preset): it replaces the
# reproduction's --preset for their runs (a recipe that sets the task as well as the agent)
VARIANT_RECIPES: dict[str, str] = {
    "mlp-playground": "playground",
    "mlp-legged-gym": "legged_gym",
}


def variant_preset(variant: str, preset: str | None) -> str | None:
    """The recipe a variant's runs start from: its own (:data:`VARIANT_RECIPES`), else
    ``preset`` (the reproduction's)."""
    return VARIANT_RECIPES.get(variant, preset)


def variant_agent(variant: str) -> tuple[str, tuple[str, ...]]:
    """The agent a variant trains and the overrides that make it that variant."""
    return VARIANTS.get(variant, (variant, ()))


def run_overrides(variant: str, overrides: list[str]) -> list[str]:
    """One run's ``--set`` values in order: the variant's settings, then the user's (which can
    change the variant's)."""
    return [*variant_agent(variant)[1], *overrides]


@dataclass
class ReproduceSettings:
    """The settings that decide a reproduction's results (see ``IDENTITY_KEYS``)."""

    variants: list[str]
    seeds: int
    total_steps: int
    num_envs: int | None = None
    sim: str | None = None
    overrides: list[str] = field(default_factory=list)
    eval_episodes: int = 5
    stage_fractions: list[float] = field(default_factory=lambda: list(STAGE_FRACTIONS))
    # seeds first_seed .. first_seed + seeds - 1: tuning on seeds that are never reported
    first_seed: int = 0
    preset: str | None = None  # cpg-actor train --preset (None: the default, paper)
    # charge each run that starts from a searched gait (agent_config.start_gait) with the
    # search's env steps (TrainConfig.search_steps): it trains total_steps minus them
    count_search_steps: bool = False

    @property
    def seed_range(self) -> range:
        return range(self.first_seed, self.first_seed + self.seeds)

    def identity(self) -> dict[str, Any]:
        data = asdict(self)
        identity = {key: data[key] for key in IDENTITY_KEYS}
        if self.first_seed:  # absent when 0: directories made before the option still match
            identity["first_seed"] = self.first_seed
        if self.preset is not None:  # likewise absent unless given
            identity["preset"] = self.preset
        if self.count_search_steps:
            identity["count_search_steps"] = True
        return identity


@dataclass(frozen=True)
class RunTask:
    """One training run and its staged evaluations (picklable: sent to Ray workers)."""

    variant: str
    seed: int
    run_dir: str
    log_path: str
    total_steps: int
    num_iterations: int
    planned_steps: int  # num_iterations x steps per iteration (>= total_steps)
    train_args: tuple[str, ...]  # the arguments after `cpg-actor train` for a fresh run
    stage_fractions: tuple[float, ...]
    eval_episodes: int
    group: str = ""  # a sweep's setting label: names stay unique across settings

    @property
    def name(self) -> str:
        prefix = f"{self.group}/" if self.group else ""
        return f"{prefix}{self.variant}/seed{self.seed}"


def parse_variants(text: str) -> list[str]:
    """``"cpg-actor,mlp"`` -> ``["cpg-actor", "mlp"]``; checked against the agent registry and
    :data:`VARIANTS`."""
    from cpg_actor.api import AGENTS

    available = sorted({*AGENTS, *VARIANTS})
    variants = [v.strip() for v in text.split(",") if v.strip()]
    if not variants:
        raise ValueError("--variants is empty; available: " + ", ".join(available))
    unknown = [v for v in variants if v not in available]
    if unknown:
        raise ValueError(
            f"unknown variant(s) {', '.join(unknown)}; available: {', '.join(available)}"
        )
    if len(set(variants)) != len(variants):
        raise ValueError(f"--variants lists a variant twice: {text}")
    return variants


def _override_keys(overrides: list[str]) -> set[str]:
    return {text.split("=", 1)[0].strip() for text in overrides}


def resolve_config(settings: ReproduceSettings, variant: str, seed: int = 0):
    """The :class:`TrainConfig` ``cpg-actor train`` will build for one run (validates it)."""
    from cpg_actor.agents.start_gait import search_steps
    from cpg_actor.api import compose_config, get_robot, without_compile_if_no_compiler

    agent = variant_agent(variant)[0]
    values = {"agent": agent, "seed": seed, "total_steps": settings.total_steps}
    if settings.num_envs is not None:
        values["num_envs"] = settings.num_envs
    if settings.sim is not None:
        values["env"] = {"sim": settings.sim}
    overrides = run_overrides(variant, settings.overrides)
    preset = variant_preset(variant, settings.preset)
    config = compose_config(preset=preset, values=values, overrides=overrides)
    from cpg_actor.api import get_agent_spec

    if settings.count_search_steps and get_agent_spec(config.agent).uses_start_gait:
        steps = search_steps(config.agent_config.start_gait, get_robot(config.robot))
        if steps:
            values["search_steps"] = steps
            config = compose_config(preset=preset, values=values, overrides=overrides)
    return without_compile_if_no_compiler(config)


def searches(config) -> bool:
    """The run's agent is trained by the open-loop search (``open-loop-es``), not PPO."""
    from cpg_actor.api import get_agent_spec

    return get_agent_spec(config.agent).trainer == "es"


def planned_iterations(config) -> tuple[int, int]:
    """``(iterations, steps per iteration)`` of a run: PPO's, or the generations of the
    open-loop search and a generation's most steps (a search never exceeds its budget)."""
    if searches(config):
        from cpg_actor.agents.open_loop_es import generation_steps, num_generations

        return num_generations(config), generation_steps(config)
    return config.num_iterations, config.steps_per_iteration


def checkpoint_interval(config) -> int:
    """Iterations between checkpoints: about ``TARGET_CHECKPOINTS`` per run, but at least two
    episodes per environment between checkpoints (so that the evaluation stages are policies
    that differ by some training; the checkpoints themselves change nothing that is trained).
    A search generation runs whole episodes: about ``TARGET_CHECKPOINTS`` of them."""
    if searches(config):
        return max(1, planned_iterations(config)[0] // TARGET_CHECKPOINTS)
    at_least = math.ceil(2 * config.env.episode_steps / config.ppo.num_steps)
    return max(1, at_least, config.num_iterations // TARGET_CHECKPOINTS)


def validate(settings: ReproduceSettings) -> None:
    check_int(settings.seeds, "--seeds", 1, MAX_SEEDS)
    from cpg_actor.api import check_seed

    check_seed(settings.first_seed, "--first-seed")
    check_seed(settings.first_seed + settings.seeds - 1, "--first-seed + --seeds - 1")
    if settings.total_steps <= 0:
        raise ValueError(f"--total-steps must be > 0, got {settings.total_steps}")
    if settings.num_envs is not None:
        check_int(settings.num_envs, "--num-envs", 1, MAX_ENVS)
    check_int(settings.eval_episodes, "--eval-episodes", 1, MAX_EPISODES)
    if "agent" in _override_keys(settings.overrides) or "seed" in _override_keys(
        settings.overrides
    ):
        raise ValueError("--set agent=... / seed=... is not allowed; use --variants / --seeds")


def thread_shares(workers: int) -> dict[str, int]:
    """The thread settings of each of ``workers`` runs sharing the machine: one torch thread
    for the rollout, and for the simulator and the update its share of the cores this process
    may use (``usable_cores``, as the runs' own automatic threads count them). Those automatic
    threads (every usable core each) would oversubscribe them, and runs side by side would
    train far slower together than one alone."""
    share = max(1, usable_cores() // max(1, workers))
    return {"torch_threads": 1, "env_threads": share, "update_threads": share}


def build_tasks(settings: ReproduceSettings, out: Path, workers: int) -> list[RunTask]:
    """One :class:`RunTask` per (variant, seed), seed by seed (every variant's seed 0, then
    every variant's seed 1, ...): the order runs start in, so that a reproduction stopped part
    way has whole seeds of every variant to compare. Raises ValueError on an invalid config."""
    validate(settings)
    keys = _override_keys(settings.overrides)
    tasks = []
    for variant in settings.variants:
        config = resolve_config(settings, variant)  # raises on unknown keys / bad values
        iterations, steps_per_iteration = planned_iterations(config)
        extra: list[str] = []
        if config.search_steps:
            extra += ["--set", f"search_steps={config.search_steps}"]
        if "checkpoint_interval" not in keys:
            extra += ["--set", f"checkpoint_interval={checkpoint_interval(config)}"]
        for key, value in thread_shares(workers).items():  # a --set of the user's wins
            if key not in keys:
                extra += ["--set", f"{key}={value}"]
        for seed in settings.seed_range:
            run_dir = out / "runs" / variant / f"seed{seed}"
            args = ["--agent", variant_agent(variant)[0], "--seed", str(seed)]
            preset = variant_preset(variant, settings.preset)
            if preset is not None:
                args += ["--preset", preset]
            args += ["--total-steps", str(settings.total_steps), "--run-dir", str(run_dir)]
            if settings.num_envs is not None:
                args += ["--num-envs", str(settings.num_envs)]
            if settings.sim is not None:
                args += ["--sim", settings.sim]
            args += extra
            for text in run_overrides(variant, settings.overrides):
                args += ["--set", text]
            args.append("--no-progress")
            tasks.append(
                RunTask(
                    variant=variant,
                    seed=seed,
                    run_dir=str(run_dir),
                    log_path=str(out / "logs" / f"{variant}_seed{seed}.log"),
                    total_steps=settings.total_steps,
                    num_iterations=iterations,
                    planned_steps=config.search_steps + iterations * steps_per_iteration,
                    train_args=tuple(args),
                    stage_fractions=tuple(settings.stage_fractions),
                    eval_episodes=settings.eval_episodes,
                )
            )
    order = {variant: i for i, variant in enumerate(settings.variants)}
    return sorted(tasks, key=lambda task: (task.seed, order[task.variant]))


def stage_warnings(tasks: list[RunTask]) -> list[str]:
    """Stages that fall before the first checkpoint after the untrained one: on a budget this
    short they are evaluated on the untrained agent (iteration 0)."""
    lines = []
    for variant in dict.fromkeys(task.variant for task in tasks):
        task = next(t for t in tasks if t.variant == variant)
        early = [
            f"{fraction:.3g}"
            for fraction in task.stage_fractions
            if 0 < fraction and round(fraction * task.num_iterations) == 0
        ]
        if early:
            lines.append(
                f"{variant}: {task.num_iterations} iterations are too few for the stage(s) at "
                f"{', '.join(early)} of training; they are evaluated on the untrained agent"
            )
    return lines


def load_settings_file(out: Path) -> dict[str, Any] | None:
    path = out / SETTINGS_FILE
    if not path.is_file():
        return None
    data = read_yaml(path) or {}  # bounded (cpg_actor.safe_yaml), one line
    if not isinstance(data, dict):
        raise ValueError(f"{path} is not a reproduce settings file")
    return data


def settings_from_file(out: Path) -> ReproduceSettings:
    data = load_settings_file(out)
    if data is None:
        raise FileNotFoundError(f"{out / SETTINGS_FILE} does not exist; is {out} a results dir?")
    saved = data["settings"]
    optional = {
        key: saved[key] for key in ("first_seed", "preset", "count_search_steps") if key in saved
    }
    return ReproduceSettings(**{key: saved[key] for key in IDENTITY_KEYS}, **optional)


def _extends(saved: dict[str, Any], new: dict[str, Any]) -> bool:
    """True when ``new`` only adds variants and/or seeds to ``saved``: every saved run is
    also a run of ``new``, with the same settings, so its results stay valid."""
    keys = (set(saved) | set(new)) - {"variants", "seeds"}
    same = all(saved.get(key) == new.get(key) for key in keys)
    saved_variants = saved.get("variants") or []
    return (
        same
        and set(saved_variants) <= set(new["variants"])
        and isinstance(saved.get("seeds"), int)
        and saved["seeds"] <= new["seeds"]
    )


def refuse_linked_out(out: Path) -> None:
    """A results directory, or a folder it writes in, that is a symbolic link is refused
    (:func:`cpg_actor.files.refuse_linked_folders`); its run directories are train's to check."""
    refuse_linked_folders(out, *(out / name for name in ("logs", "figures", "runs")))


def prepare_out_dir(out: Path, settings: ReproduceSettings, overwrite: bool) -> str:
    """Create ``out`` or check that it holds the same reproduction; returns "new", "resume",
    "extend" (the same reproduction with more variants or seeds: finished runs are kept) or
    "overwrite". Refuses an existing directory made with other settings (or not made by
    ``cpg-actor reproduce``) unless ``overwrite``, which clears it only if it carries the
    project's marker and holds nothing but what the project wrote
    (:func:`cpg_actor.files.clear_project_dir`)."""
    if out.exists() and not out.is_dir():
        raise NotADirectoryError(f"--out {out} is a file, not a directory")
    refuse_linked_out(out)
    saved = load_settings_file(out)
    if out.exists() and any(out.iterdir()):
        if saved is None:
            raise FileExistsError(
                f"{out} is not empty and was not written by `cpg-actor reproduce` "
                f"(no {SETTINGS_FILE}); choose another --out"
            )
        if saved.get("settings") == settings.identity() and not overwrite:
            return "resume"
        if not overwrite and _extends(saved.get("settings", {}), settings.identity()):
            return "extend"
        if not overwrite:
            differences = [
                f"{key}: {brief(saved.get('settings', {}).get(key))} -> {brief(value)}"
                for key, value in settings.identity().items()
                if saved.get("settings", {}).get(key) != value
            ]
            raise FileExistsError(
                f"{out} holds a reproduction with other settings ({'; '.join(differences)}); "
                "only more variants or seeds may be added to it; pass --overwrite to replace "
                "it or choose another --out"
            )
        clear_project_dir(out, RESULTS, keep=(MARKER,))
        return "overwrite"
    out.mkdir(parents=True, exist_ok=True)
    write_marker(out, RESULTS)
    return "new"


def write_settings_file(
    out: Path, settings: ReproduceSettings, command: str, execution: dict[str, Any]
) -> None:
    data = {
        "command": command,
        "settings": settings.identity(),
        "execution": execution,  # may differ between invocations (workers, Ray address)
    }
    atomic_write_text(yaml.safe_dump(data, sort_keys=False), out / SETTINGS_FILE)
