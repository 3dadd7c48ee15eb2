"""`cpg-actor train`: train an agent (PPO, or the open-loop search) on a robot; resumable run
directory."""

from __future__ import annotations

import argparse
import shlex
import signal
import sys
import threading
from pathlib import Path

from cpg_actor.commands import add_set_option
from cpg_actor.config import (
    TrainConfig,
    check_seed,
    compose_config,
    parse_steps,
    without_compile_if_no_compiler,
)
from cpg_actor.config.presets import PRESETS
from cpg_actor.files import (
    MARKER,
    RUN,
    atomic_write_text,
    check_directory_path,
    check_overwritable,
    check_path_given,
    check_run_dir_length,
    clear_project_dir,
    marker_kind,
    refuse_link,
    refuse_linked_folders,
    remove_stale_temporaries,
    write_marker,
)
from cpg_actor.limits import MAX_ENVS, MAX_SEEDS, check_int
from cpg_actor.robots.registry import ROBOTS, all_simulators, get_robot
from cpg_actor.training.progress import evaluation_text, metrics_text
from cpg_actor.training.run_lock import LOCK_NAME, RunLock

HELP = (
    "train an agent (cpg-actor, cpg-actor-paper, mlp, mlp-warm, cho2019-warm, ...) with PPO, "
    "or search one (open-loop-es: CMA-ES)"
)

DEFAULT_RUN_DIR = "runs/{agent}_{sim}_seed{seed}"
DEFAULT_GROUP_DIR = "runs/{agent}_{sim}_seeds{first}-{last}"  # --seeds K


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from cpg_actor.agents import AGENTS

    parser.add_argument(
        "--agent", default=None, help=f"one of {', '.join(sorted(AGENTS))} (default cpg-actor)"
    )
    parser.add_argument(
        "--robot",
        default=None,
        choices=sorted(ROBOTS),
        help="the robot (cpg_actor.robots.registry; default hopper, the paper's leg on a rail; "
        "the quadrupeds: docs/quadruped.md, docs/go1.md)",
    )
    parser.add_argument(
        "--sim",
        default=None,
        choices=all_simulators(),
        help="physics backend (default mujoco; mjx: MuJoCo XLA on JAX's device, docs/gpu.md)",
    )
    parser.add_argument(
        "--preset",
        default=None,
        choices=sorted(PRESETS),
        help="the recipe, the starting config values: paper (OpenAI Baselines' ppo2 MuJoCo "
        "settings), throughput (fewer, larger gradient steps; see docs/training.md) or gpu "
        "(4,096 MJX envs on the GPU; docs/gpu.md); default: the robot's (the hopper's paper, "
        "the quadrupeds' throughput, with each agent's tuned settings on it)",
    )
    parser.add_argument("--seed", type=int, default=None, help="random seed (default 0)")
    parser.add_argument(
        "--seeds",
        type=int,
        default=None,
        metavar="K",
        help="train K seeds (--seed, --seed + 1, ...) in one process over one batched env, "
        'each a run of its own in RUN_DIR/seed-S (docs/gpu.md, "Many seeds in one '
        'process"; PPO agents without a warm start)',
    )
    parser.add_argument(
        "--total-steps",
        default=None,
        help=f"control steps over all envs, e.g. 300k or 20M (default {TrainConfig.total_steps:,})",
    )
    parser.add_argument(
        "--num-envs", type=int, default=None, help=f"parallel envs (default {TrainConfig.num_envs})"
    )
    parser.add_argument(
        "--device",
        default=None,
        help="networks, storage and PPO: cpu (default), cuda, cuda:N or auto; the simulator "
        "stays on the CPU, except --sim mjx (on JAX's device)",
    )
    parser.add_argument(
        "--run-dir", default=None, help=f"output directory (default {DEFAULT_RUN_DIR})"
    )
    parser.add_argument(
        "--config", default=None, help="YAML file with config values (nested like config.yaml)"
    )
    add_set_option(
        parser,
        "override a config value on its dotted path, e.g. ppo.learning_rate=1e-4 (repeatable)",
    )
    parser.add_argument(
        "--resume",
        action="store_true",
        help="continue the run in --run-dir from its last checkpoint (with --seeds K: the group "
        "of seeds in --run-dir, from their last common checkpoint)",
    )
    parser.add_argument(
        "--overwrite", action="store_true", help="replace an existing run directory"
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument(
        "--progress-interval",
        type=float,
        default=30.0,
        help="seconds between plain progress lines when stdout is not a terminal (default 30)",
    )


def simulator(config: TrainConfig) -> str:
    """The run's simulator, prefixed by the robot when it is not the default robot
    ("anymal-mujoco"; the default's runs keep their names, "mujoco")."""
    sim = get_robot(config.robot).simulator(config.env)
    return sim if config.robot == TrainConfig.robot else f"{config.robot}-{sim}"


def build_config(args: argparse.Namespace) -> TrainConfig:
    """The flags as config values, composed by :func:`cpg_actor.config.compose_config`
    (defaults, preset, --config, the flags, each --set)."""
    flags: dict = {}
    if args.agent is not None:
        flags["agent"] = args.agent
    if args.seed is not None:
        flags["seed"] = args.seed
    if args.total_steps is not None:
        flags["total_steps"] = parse_steps(args.total_steps)
    if args.num_envs is not None:
        flags["num_envs"] = args.num_envs
    if getattr(args, "robot", None) is not None:
        flags["robot"] = args.robot
    if args.sim is not None:
        chosen = get_robot(flags.get("robot", TrainConfig.robot)).simulator_config(args.sim)
        if chosen:
            flags["env"] = chosen
    if getattr(args, "device", None) is not None:
        flags["device"] = args.device
    config = compose_config(getattr(args, "preset", None), args.config, flags, args.overrides)
    return without_compile_if_no_compiler(config)


def _has_content(run_dir: Path) -> bool:
    """``run_dir`` holds something: anything but its run marker and lock file (a start
    stopped before its first write), and those too in a folder without the marker."""
    if not run_dir.is_dir():
        return False
    ours = (MARKER, LOCK_NAME) if marker_kind(run_dir) == RUN else ()
    return any(p.name not in ours or p.is_symlink() for p in run_dir.iterdir())


def check_run_dir_path(run_dir: Path) -> None:
    """One clear error, before anything starts, for a ``--run-dir`` that cannot be one: a
    file, a path through a file, a path too long for the files written in it, or a symbolic
    link (it, or the folders train writes in it: they may lead into a user's folder)."""
    check_directory_path(run_dir, "run directory")
    check_run_dir_length(run_dir)
    refuse_linked_folders(run_dir, run_dir / "checkpoints", run_dir / "tensorboard")


def prepare_run_dir(run_dir: Path, overwrite: bool) -> None:
    """Create ``run_dir``; an existing non-empty one is cleared only with ``overwrite``, only
    if it carries the project's marker and only of what the project wrote (a directory
    holding anything else is refused, see :func:`cpg_actor.files.clear_project_dir`). Its lock
    file is kept (the caller holds the lock)."""
    if _has_content(run_dir):
        if not overwrite:
            raise FileExistsError(
                f"run directory {run_dir} already exists; pass --resume to continue it or "
                "--overwrite to replace it"
            )
        clear_project_dir(run_dir, RUN, keep=(LOCK_NAME, MARKER))
    run_dir.mkdir(parents=True, exist_ok=True)


def run(args: argparse.Namespace) -> int:
    locks: list[RunLock] = []
    try:
        return _run(args, locks)
    finally:
        for lock in locks:
            lock.release()


def _lock(run_dir: Path, locks: list[RunLock]) -> None:
    """Hold ``run_dir``'s lock until the command ends (RunInUseError if another run has it)."""
    locks.append(RunLock(run_dir).acquire())


def _searches(config: TrainConfig) -> bool:
    """The agent is trained by the open-loop search (``AgentSpec.trainer == "es"``)."""
    from cpg_actor.agents import get_agent_spec

    return get_agent_spec(config.agent).trainer == "es"


def _runner(config: TrainConfig, run_dir: Path, args: argparse.Namespace):
    if _searches(config):
        from cpg_actor.training.es_runner import ESRunner as Runner
    else:
        from cpg_actor.training.runner import Runner

    return Runner(
        config, run_dir, progress=not args.no_progress, progress_interval=args.progress_interval
    )


def _run(args: argparse.Namespace, locks: list[RunLock]) -> int:
    """Build the run (a new one, or the one in ``--run-dir`` resumed), train it, report."""
    check_path_given(args.run_dir, "--run-dir")
    check_path_given(args.config, "--config")
    if getattr(args, "seeds", None) is not None:
        return _run_group(args, locks)
    if args.resume:
        runner, run_dir = _resumed_runner(args, locks)
        if runner is None:  # a finished run or an ended search: nothing to continue, no error
            return 0
    else:
        runner, run_dir = _new_runner(args, locks)
    code = _learn(runner, lambda: (
        f"interrupted at iteration {runner.iteration}; last checkpoint "
        f"{runner.last_checkpoint_path()}; continue with --resume --run-dir {run_dir}"
    ))  # fmt: skip
    if code is None:
        print(_search_done_text(runner) if _searches(runner.config) else _done_text(runner))
    return code or 0


def _run_group(args: argparse.Namespace, locks: list[RunLock]) -> int:
    """``--seeds K``: K runs of the config, seeds ``config.seed`` on, trained together by a
    :class:`~cpg_actor.training.many_seeds.SeedGroup`, new (each seed's run directory prepared
    and locked as a single run's) or resumed (``--resume``: the group in ``--run-dir``)."""
    check_int(args.seeds, "--seeds", 1, MAX_SEEDS)
    if args.resume:
        group = _resumed_group(args, locks)
        if group is None:  # finished: nothing to continue, no error
            return 0
    else:
        group = _new_group(args, locks)
    run_dir = group.runners[0].run_dir.parent
    code = _learn(group, lambda: (
        f"interrupted; each seed's last checkpoint is in {run_dir}/seed-S/checkpoints; "
        f"continue the group: --seeds {len(group.seeds)} --resume --run-dir {run_dir}"
    ))  # fmt: skip
    if code is None:
        for runner in group.runners:
            print(f"seed {runner.config.seed}: {_done_text(runner)}")
    return code or 0


def _new_group(args: argparse.Namespace, locks: list[RunLock]):
    """A new group of ``--seeds`` runs from the flags, every seed's run directory prepared
    under its lock (an existing one refused before anything is built, unless ``--overwrite``;
    every seed's lock taken before any seed's run is cleared)."""
    from cpg_actor.training.many_seeds import SeedGroup, seed_dir

    config = build_config(args)
    if _searches(config):
        raise ValueError(
            f"--seeds trains PPO agents; {config.agent} is searched by CMA-ES: one seed per "
            "process (--seed)"
        )
    if args.seeds * config.num_envs > MAX_ENVS:  # one batched env holds them all
        raise ValueError(
            f"--seeds x num_envs ({args.seeds:,} x {config.num_envs:,}) envs are above the "
            f"{MAX_ENVS:,} accepted in one process; use fewer seeds or envs"
        )
    check_seed(config.seed + args.seeds - 1, "--seed + --seeds - 1")
    seeds = list(range(config.seed, config.seed + args.seeds))
    run_dir = Path(
        args.run_dir
        or DEFAULT_GROUP_DIR.format(
            agent=config.agent, sim=simulator(config), first=seeds[0], last=seeds[-1]
        )
    )
    check_run_dir_path(run_dir)
    directories = [seed_dir(run_dir, seed) for seed in seeds]
    for directory in directories:  # refused before anything is built or written
        check_run_dir_path(directory)
        if _has_content(directory):
            if not args.overwrite:
                raise FileExistsError(
                    f"run directory {directory} already exists; pass --overwrite to replace "
                    f"the group's runs, or continue that seed alone: --resume --run-dir "
                    f"{directory}"
                )
            check_overwritable(directory, RUN)
    group = SeedGroup(
        config, seeds, run_dir, tensorboard=True, progress=not args.no_progress,
        progress_interval=args.progress_interval,
    )  # fmt: skip
    try:
        for directory in directories:  # every seed's lock before any seed's run is cleared
            if not _has_content(directory):
                directory.mkdir(parents=True, exist_ok=True)
                write_marker(directory, RUN)
            _lock(directory, locks)
        for directory in directories:
            prepare_run_dir(directory, args.overwrite)
        for runner in group.runners:
            runner.config.save(runner.run_dir / "config.yaml")
    except BaseException:
        group.close()
        raise
    print(f"{len(seeds)} seeds ({seeds[0]}-{seeds[-1]}) in one process, "
          f"{len(seeds)} x {config.num_envs} envs; "
          + _start_text(config, run_dir, args).replace(
              f"run directory {run_dir}", f"runs in {run_dir}/seed-S"))  # fmt: skip
    return group


def _resumed_group(args: argparse.Namespace, locks: list[RunLock]):
    """The group in ``--run-dir`` at its seeds' last common checkpoint, under every seed's
    lock (cpg_actor.training.many_seeds: it continues exactly as the uninterrupted group);
    None for a group that has finished (said so)."""
    from cpg_actor.training.checkpoint import load_checkpoint, resume_checkpoint
    from cpg_actor.training.many_seeds import SeedGroup, seed_dir

    _check_resume_flags(args)
    run_dir = Path(args.run_dir)
    check_run_dir_path(run_dir)
    found = sorted(
        (int(path.name[len("seed-") :]), path)
        for path in (run_dir.glob("seed-*") if run_dir.is_dir() else ())
        if path.name[len("seed-") :].isdigit() and any(path.glob("checkpoints/*.pt"))
    )
    if not found:
        raise FileNotFoundError(
            f"{run_dir} holds no seed's run with a checkpoint (seed-S/checkpoints); nothing "
            "to resume"
        )
    _, first_data, _ = resume_checkpoint(found[0][1])
    seeds = (first_data.get("seed_group") or {}).get("seeds")
    alone = (f"continue each seed alone: --resume --run-dir {run_dir}/seed-S (not as the "
             "group would)")  # fmt: skip
    if not seeds:
        raise ValueError(
            f"{found[0][1]}'s last checkpoint is not a seed group's (resumed alone since, or "
            f"written before groups resumed); {alone}"
        )
    if len(seeds) != args.seeds:
        raise ValueError(
            f"{run_dir} is a group of {len(seeds)} seeds ({seeds[0]}-{seeds[-1]}); resume it "
            f"with --seeds {len(seeds)}"
        )
    directories = [seed_dir(run_dir, seed) for seed in seeds]
    for directory in directories:  # refused before anything is written
        check_run_dir_path(directory)
        if not any((directory / "checkpoints").glob("*.pt")):
            raise FileNotFoundError(f"{directory} holds no checkpoint; {alone}")
        refuse_link(directory / "metrics.jsonl")  # appended to
    for directory in directories:  # every seed's lock before anything is written
        _lock(directory, locks)
    newest = []
    for k, directory in enumerate(directories):
        remove_stale_temporaries(directory)
        path, data, notes = resume_checkpoint(directory)
        for note in notes:
            print(f"cpg-actor train: {directory}: {note}", file=sys.stderr)
        if data.get("seed_group") != {"seeds": seeds, "index": k}:
            raise ValueError(
                f"{directory}'s last checkpoint ({path.name}) is not this group's (the seed was "
                f"resumed alone since); {alone}"
            )
        newest.append((path, data["iteration"]))
    common = min(iteration for _, iteration in newest)  # a kill can cut the seeds' writes
    paths = []
    for directory, (path, iteration) in zip(directories, newest, strict=True):
        if iteration != common:
            path = directory / "checkpoints" / f"iter_{common:06d}.pt"
            if not path.is_file() or load_checkpoint(path).get("iteration") != common:
                raise ValueError(
                    f"{path} (the seeds' last common iteration, {common}) is missing or not "
                    f"of that iteration; {alone}"
                )
        paths.append(path)
    configs = [_resume_config(directory)[1] for directory in directories]
    config = configs[0]
    for seed, other in zip(seeds, configs, strict=True):
        if other.to_dict() != {**config.to_dict(), "seed": seed}:
            raise ValueError(f"{seed_dir(run_dir, seed)}/config.yaml differs from the first "
                             "seed's in more than its seed: not one group")  # fmt: skip
    if args.total_steps is not None:
        config.total_steps = parse_steps(args.total_steps)
    config.validate()
    group = SeedGroup(
        config, seeds, run_dir, tensorboard=True, progress=not args.no_progress,
        progress_interval=args.progress_interval,
    )  # fmt: skip
    try:
        group.resume(paths)
        first = group.runners[0]
        _check_unfinished(first, resized=args.total_steps is not None)
        if _finished(first):
            group.close()
            print(f"the group in {run_dir} is finished at iteration {first.iteration} "
                  f"({first.global_step:,} steps per seed); nothing to continue (pass a "
                  "larger --total-steps to train it further)")  # fmt: skip
            return None
        for runner in group.runners:
            runner.config.save(runner.run_dir / "config.yaml")
            _truncate_metrics(runner.run_dir / "metrics.jsonl", runner.iteration)
    except BaseException:
        group.close()
        raise
    print(f"resuming the group of {len(seeds)} seeds ({seeds[0]}-{seeds[-1]}) in {run_dir} at "
          f"iteration {first.iteration} ({first.global_step:,} steps per seed)")  # fmt: skip
    return group


def _check_resume_flags(args: argparse.Namespace) -> None:
    """A resumed run takes its saved config: only ``--total-steps`` may change."""
    if args.run_dir is None:
        raise ValueError("--resume needs --run-dir")
    given = [
        flag
        for flag, value in (
            ("--agent", args.agent),
            ("--preset", args.preset),
            ("--sim", args.sim),
            ("--device", args.device),
            ("--seed", args.seed),
            ("--num-envs", args.num_envs),
            ("--config", args.config),
            ("--set", args.overrides or None),
        )
        if value is not None
    ]
    if given:
        raise ValueError(
            f"a resumed run uses its saved config.yaml; only --total-steps may change "
            f"(got {', '.join(given)})"
        )
    if args.overwrite:
        raise ValueError("--resume and --overwrite exclude each other")


def _resumed_runner(args: argparse.Namespace, locks: list[RunLock]):
    """The runner of ``--run-dir`` at its last checkpoint, under the run's lock, and the run
    directory; no runner for a search that has ended (said so)."""
    _check_resume_flags(args)
    run_dir = Path(args.run_dir)
    check_run_dir_path(run_dir)
    if not run_dir.is_dir():
        raise FileNotFoundError(f"run directory {run_dir} does not exist; nothing to resume")
    if not any((run_dir / "checkpoints").glob("*.pt")):  # refused before the lock is made
        raise FileNotFoundError(
            f"{run_dir / 'checkpoints'} holds no checkpoint (last.pt, iter_*.pt); nothing to resume"
        )
    refuse_link(run_dir / "metrics.jsonl")  # appended to: refused before anything is written
    _lock(run_dir, locks)
    remove_stale_temporaries(run_dir)  # of writes a killed run left unfinished
    checkpoint, config = _resume_config(run_dir)
    if args.total_steps is not None:
        config.total_steps = parse_steps(args.total_steps)
    config.validate()
    runner = _runner(config, run_dir, args)
    try:
        runner.load_checkpoint(checkpoint)
        _check_unfinished(runner, resized=args.total_steps is not None)
        group = getattr(runner, "resumed_out_of_group", None)
        if group is not None and len(group["seeds"]) > 1:
            seeds = group["seeds"]
            print(f"note: {run_dir} is a seed of a group of {len(seeds)} seeds trained in one "
                  "process; resumed alone it continues as a run of its own, from new "
                  "episodes, not equal to the group continued (--seeds "
                  f"{len(seeds)} --resume --run-dir {run_dir.parent})")  # fmt: skip
    except (ValueError, FileNotFoundError):
        runner.close()
        raise
    if _finished(runner):  # nothing to continue, and no error (_check_unfinished)
        runner.close()
        print(_search_finished_text(runner) if _searches(config) else _finished_text(runner))
        return None, run_dir
    config.save(run_dir / "config.yaml")
    try:
        _truncate_metrics(run_dir / "metrics.jsonl", runner.iteration)
    except ValueError:
        runner.close()
        raise
    print(f"resuming {run_dir} at iteration {runner.iteration} ({runner.global_step:,} steps)")
    print(_logs_text(run_dir))
    return runner, run_dir


def _finished(runner) -> bool:
    """The resumed run has no steps left."""
    if _searches(runner.config):
        return runner.finished
    return runner.iteration >= runner.config.num_iterations


def _check_unfinished(runner, resized: bool) -> None:
    """ValueError if the resumed run has no steps left, except where that is no error: a
    search that CMA-ES stopped, and a finished run resumed as it is (``resized``: a
    ``--total-steps`` it has already reached was given)."""
    if not _finished(runner):
        return
    if _searches(runner.config):
        if not runner.stop_reason:
            raise ValueError(_search_finished_text(runner))
    elif resized:
        raise ValueError(
            f"the run is already at iteration {runner.iteration} "
            f"({runner.global_step:,} steps); pass a larger --total-steps to continue"
        )


def _finished_text(runner) -> str:
    return (
        f"{runner.run_dir} is finished at iteration {runner.iteration} "
        f"({runner.global_step:,} steps); nothing to continue (pass a larger --total-steps "
        "to train it further)"
    )


def _new_runner(args: argparse.Namespace, locks: list[RunLock]):
    """The runner of a new run from the flags, its run directory prepared under its lock
    (an existing one is refused before anything is built, unless ``--overwrite``)."""
    config = build_config(args)
    run_dir = Path(
        args.run_dir
        or DEFAULT_RUN_DIR.format(agent=config.agent, sim=simulator(config), seed=config.seed)
    )
    check_run_dir_path(run_dir)
    if _has_content(run_dir):  # refused before anything is built or written
        if not args.overwrite:
            prepare_run_dir(run_dir, overwrite=False)
        check_overwritable(run_dir, RUN)
    runner = _runner(config, run_dir, args)
    try:
        if not _has_content(run_dir):  # marked first: its lock file is then its own
            run_dir.mkdir(parents=True, exist_ok=True)
            write_marker(run_dir, RUN)
        _lock(run_dir, locks)  # before --overwrite deletes anything
        prepare_run_dir(run_dir, args.overwrite)  # checked again, under the lock
    except BaseException:
        runner.close()
        raise
    config.save(run_dir / "config.yaml")
    if _searches(config):
        print(_search_start_text(runner, run_dir, args))
    else:
        print(_start_text(config, run_dir, args))
    print(_logs_text(run_dir))
    return runner, run_dir


def _start_text(config: TrainConfig, run_dir: Path, args: argparse.Namespace) -> str:
    """What a new PPO run will do (and a note when the budget is not whole iterations)."""
    lines = []
    planned = config.search_steps + config.num_iterations * config.steps_per_iteration
    if planned != config.total_steps and _budget_asked(args):
        lines.append(
            f"note: {config.total_steps:,} steps is not a whole number of iterations "
            f"of {config.steps_per_iteration:,}; training {planned:,}"
        )
    searched = (
        f", the first {config.search_steps:,} spent by the search for its start gait"
        if config.search_steps
        else ""
    )
    lines.append(
        f"training {config.agent} ({config.preset} preset) on {simulator(config)} for "
        f"{config.total_steps:,} steps "
        f"({config.num_iterations} iterations of {config.steps_per_iteration} steps"
        f"{searched}), run directory {run_dir}"
    )
    return "\n".join(lines)


class Terminated(KeyboardInterrupt):
    """SIGTERM during training: stopped as Ctrl-C stops it (a run started in the background
    by a script ignores SIGINT, so SIGTERM is how it is stopped)."""


def _raise_terminated(signum, frame):
    raise Terminated


def _learn(runner, interrupted) -> int | None:
    """Train ``runner`` (a run, or a group of seeds: anything with ``learn`` and ``close``);
    the exit status of a run that stopped early (None: it ran to its end). ``interrupted()``:
    what Ctrl-C (or SIGTERM: exit 143) leaves and how to continue."""
    from cpg_actor.training.runner import TrainingDiverged

    main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _raise_terminated) if main else None
    try:
        runner.learn()
    except TrainingDiverged as error:
        print(f"cpg-actor train: training stopped: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as stop:
        print(f"cpg-actor train: {interrupted()}", file=sys.stderr)
        return 143 if isinstance(stop, Terminated) else 130
    finally:
        if main:  # None: a handler not installed from Python, taken as the default
            signal.signal(signal.SIGTERM, signal.SIG_DFL if previous is None else previous)
        runner.close()
    return None


def _done_text(runner) -> str:
    """The last line of a PPO run: steps, time, the training episodes' return and metrics,
    the last evaluation, the checkpoint."""
    row = getattr(runner, "last_row", {})
    evaluation = getattr(runner, "last_evaluation", None)
    evaluated = f"; deterministic {evaluation_text(evaluation)}" if evaluation else ""
    episode_return = row.get("charts/episode_return", float("nan"))
    training = (
        " ".join(
            [
                f"mean episode return {episode_return:.3f}",
                metrics_text(runner.rollout.episodes.env_metrics()),
            ]
        ).rstrip()
        if episode_return == episode_return
        else "no training episode finished (runs shorter than an episode)"
    )
    return (
        f"done: {runner.global_step:,} steps in {runner.train_wall:.0f} s of training, "
        f"{training}{evaluated}; checkpoint {runner.last_checkpoint_path()}"
    )


def _budget_asked(args: argparse.Namespace) -> bool:
    """The user gave the budget (``--total-steps``, ``--set total_steps=...`` or a ``--config``
    file's ``total_steps``), rather than taking the default."""
    from cpg_actor.config import read_config_file

    if args.total_steps is not None:
        return True
    if any(text.partition("=")[0].strip() == "total_steps" for text in args.overrides or ()):
        return True
    return args.config is not None and "total_steps" in read_config_file(Path(args.config))


def _logs_text(run_dir: Path) -> str:
    """Where the run's logs go, and the command that shows them."""
    return (
        f"logs: {run_dir / 'metrics.jsonl'}; TensorBoard: tensorboard --logdir "
        f"{shlex.quote(str(run_dir / 'tensorboard'))}"
    )


def _search_start_text(runner, run_dir: Path, args: argparse.Namespace) -> str:
    """What a new open-loop search will do (cpg_actor.training.es_runner)."""
    config, es = runner.config, runner.config.es
    lines = []
    if args.num_envs is not None:
        lines.append(
            f"note: --num-envs is not used by the search; it runs es.popsize x es.episodes = "
            f"{es.popsize * es.episodes} envs"
        )
    if runner.planned_steps != config.total_steps and _budget_asked(args):
        lines.append(
            f"note: {config.total_steps:,} steps is not a whole number of generations of "
            f"{runner.generation_steps:,}; searching {runner.planned_steps:,} (a search never "
            "exceeds its budget)"
        )
    lines.append(
        f"searching {config.agent} (CMA-ES, sigma0 {es.sigma0:g}) on {simulator(config)} for "
        f"{runner.planned_steps:,} steps ({runner.num_generations} generations of {es.popsize} "
        f"candidates x {es.episodes} episode{'s' if es.episodes > 1 else ''}, "
        f"{runner.generation_steps:,} steps), run directory {run_dir}"
    )
    return "\n".join(lines)


def _search_finished_text(runner) -> str:
    where = f"generation {runner.iteration} ({runner.global_step:,} steps)"
    if runner.stop_reason:
        return (
            f"the search ended at {where}: CMA-ES stopped ({runner.stop_reason}); nothing to "
            "continue (start a new run to search again)"
        )
    return f"the search is already at {where}; pass a larger --total-steps to continue"


def _search_done_text(runner) -> str:
    evaluation = runner.last_evaluation
    evaluated = f"; deterministic {evaluation_text(evaluation)}" if evaluation else ""
    stopped = f" (CMA-ES stopped: {runner.stop_reason})" if runner.stop_reason else ""
    return (
        f"done: {runner.global_step:,} steps in {runner.train_wall:.0f} s of search, "
        f"{runner.iteration} generations{stopped}; best return "
        f"{runner.search.best_fitness:.3f} (generation {runner.search.best_generation})"
        f"{evaluated}; gait {runner.gait_path()}; checkpoint {runner.last_checkpoint_path()}"
    )


def _resume_config(run_dir: Path) -> tuple[Path, TrainConfig]:
    """The checkpoint to resume from and the run's config, checked against each other: a
    missing ``config.yaml`` is rebuilt from the checkpoint; one edited since (any key but
    ``total_steps``) is refused, since the resumed run would not continue the same run."""
    from cpg_actor.training.checkpoint import config_differences, resume_checkpoint

    checkpoint, data, notes = resume_checkpoint(run_dir)
    for note in notes:
        print(f"cpg-actor train: {note}; resuming from {checkpoint.name}", file=sys.stderr)
    saved = TrainConfig.from_dict(data["config"])
    config_path = run_dir / "config.yaml"
    if not config_path.is_file():
        saved.save(config_path)
        print(f"cpg-actor train: {config_path} was missing; rebuilt from {checkpoint.name}")
    config = TrainConfig.load(config_path)
    changed = [
        key for key in config_differences(config.to_dict(), saved.to_dict()) if key != "total_steps"
    ]
    if changed:
        raise ValueError(
            f"{config_path} differs from the config the run was trained with (in "
            f"{checkpoint.name}) at {', '.join(changed)}; resuming would not continue the same "
            "run. Undo the edit, or start a new run with the new values"
        )
    return checkpoint, config


def _truncate_metrics(path: Path, iteration: int) -> None:
    """Drop metric rows logged after the checkpoint a run resumes from, and a last row cut
    off by a kill while it was written (with a note); a damaged row before it is an error."""
    if not path.is_file():
        return
    import json

    lines = [line for line in path.read_text().splitlines() if line.strip()]
    kept = []
    for number, line in enumerate(lines, 1):
        try:
            row = json.loads(line)
        except ValueError:
            if number < len(lines):
                raise ValueError(
                    f"{path}, line {number}: not a row of metrics (JSON); resuming would "
                    "append to a damaged log: repair or remove that line"
                ) from None
            print(f"cpg-actor train: {path}: its last row is cut off (a run killed while "
                  "writing it); dropped", file=sys.stderr)  # fmt: skip
            break
        if not isinstance(row, dict):  # a cut-off row starts with "{": never parses as this
            raise ValueError(
                f"{path}, line {number}: not a row of metrics (a JSON object); resuming would "
                "append to a damaged log: repair or remove that line"
            )
        if row.get("iteration", 0) <= iteration:
            kept.append(line)
    if len(kept) != len(lines):
        atomic_write_text("".join(line + "\n" for line in kept), path)
