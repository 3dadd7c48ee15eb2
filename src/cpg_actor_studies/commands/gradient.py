"""`cpg-actor gradient`: how much of the full-trajectory gradient the k-step CPG replay keeps.

See :mod:`cpg_actor_studies.gradient`. Example (a trained run, and the untrained default
CPG-Actor)::

    cpg-actor gradient --run runs/cpg0 --out gradient/trained.md
    cpg-actor gradient --out gradient/untrained.md
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from cpg_actor.limits import brief

HELP = "measure the k-step (truncated) CPG gradient against the full-trajectory one"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--run", default=None, help="a cpg-actor run directory (default: the untrained agent)"
    )
    parser.add_argument(
        "--ks", default="1,2,4,8,16,32", help="replay lengths k, comma-separated (1: the paper)"
    )
    parser.add_argument("--envs", type=int, default=8, help="envs in the rollout (default 8)")
    parser.add_argument("--steps", type=int, default=500, help="control steps (default 500)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default=None, help="write the table here (.md; .json beside it)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")


def parse_ks(text: str, steps: int) -> list[int]:
    try:
        ks = [int(k) for k in text.split(",") if k.strip()]
    except ValueError:
        raise ValueError(f"--ks must be comma-separated integers, got {brief(text)}") from None
    if not ks or any(not 1 <= k <= steps for k in ks):
        raise ValueError(f"--ks must be integers in [1, --steps={steps}], got {brief(text)}")
    return ks


def build_policy(run: str | None, seed: int):
    """The run's policy, or the default untrained CPG-Actor built with ``seed``."""
    import torch

    from cpg_actor.api import (
        CPGActorAgent,
        Policy,
        TrainConfig,
        get_agent_spec,
        get_robot,
        load_policy,
        make_env,
    )
    from cpg_actor.ppo.normalizer import RunningNormalizer

    if run is not None:
        if not (Path(run) / "checkpoints" / "last.pt").is_file():
            raise FileNotFoundError(f"{run}/checkpoints/last.pt does not exist: not a run?")
        policy = load_policy(run)
        config = policy.config
    else:
        config = TrainConfig(agent="cpg-actor", seed=seed)
        torch.manual_seed(seed)
        robot = get_robot(config.robot)
        env = make_env(config, robot, 1, 1)
        agent = get_agent_spec("cpg-actor").build(config.agent_config, env, robot)
        low, high = env.single_action_space.low, env.single_action_space.high
        normalizer = RunningNormalizer(int(env.single_observation_space.shape[0]))
        env.close()
        policy = Policy(agent, normalizer, low, high, normalize_observations=False)
        policy.config = config
    if not isinstance(policy.agent, CPGActorAgent) or policy.agent.feedback is None:
        raise ValueError(
            f"the gradient study needs a CPG-Actor with feedback (agent cpg-actor), "
            f"got '{config.agent}'"
        )
    return policy, config


def markdown(result: dict, share: float | None, title: str) -> str:
    groups = [key.split("/", 1)[1] for key in result["full"]]
    lines = [
        f"# {title}",
        "",
        "Cosine between the k-step and the full-trajectory gradient of the PPO surrogate, and",
        "(in brackets) the ratio of their norms, per parameter group.",
        "",
        "| replay | " + " | ".join(groups) + " |",
        "| --- | " + " | ".join("---:" for _ in groups) + " |",
    ]
    for label, row in result.items():
        if label == "full":
            continue
        cells = [f"{row[f'cos/{g}']:.3f} ({row[f'norm/{g}']:.3g})" for g in groups]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    norms = ", ".join(f"{g} {result['full'][f'norm/{g}']:.3g}" for g in groups)
    lines += ["", f"Full-trajectory gradient norms: {norms}."]
    if share is not None:
        lines.append(
            f"Sampled feedback: its own score gives the feedback network a gradient "
            f"{share:.3g} times the norm of the one through the CPG step."
        )
    return "\n".join(lines) + "\n"


def run(args: argparse.Namespace) -> int:

    from cpg_actor.api import MAX_EPISODES, atomic_write_text, check_seed
    from cpg_actor.limits import MAX_EPISODE_STEPS, check_int
    from cpg_actor.robots.common.torch_env import TorchVectorEnv
    from cpg_actor_studies.gradient import collect_rollout, feedback_score_share, truncation_study

    check_int(args.envs, "--envs", 1, MAX_EPISODES)  # an episode each, kept for the gradient
    check_int(args.steps, "--steps", 2, MAX_EPISODE_STEPS)
    check_seed(args.seed)
    ks = parse_ks(args.ks, args.steps)
    out = Path(args.out) if args.out else None
    if out is not None:
        if out.suffix != ".md":
            raise ValueError(f"--out must end in .md, got {out}")
        if out.exists() and not args.overwrite:
            raise FileExistsError(f"{out} exists; pass --overwrite to replace it")
    policy, config = build_policy(args.run, args.seed)
    from cpg_actor.api import get_robot, make_env

    env = TorchVectorEnv(make_env(config, get_robot(config.robot), args.envs, None))
    try:
        rollout = collect_rollout(policy, env, args.steps, args.seed, config.ppo.gamma)
    finally:
        env.close()
    agent = policy.agent
    result = truncation_study(agent, rollout, ks)
    share = feedback_score_share(agent, rollout)
    source = f"run {args.run}" if args.run else f"the untrained CPG-Actor (seed {args.seed})"
    text = markdown(result, share, f"Truncated CPG gradient: {source}")
    command = (
        f"cpg-actor gradient{f' --run {args.run}' if args.run else ''} --ks {args.ks} "
        f"--envs {args.envs} --steps {args.steps} --seed {args.seed}"
    )
    text += f"\n{args.envs} envs x {args.steps} steps, sampled actions. Command: `{command}`\n"
    print(text)
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(text, out)
        data = {"command": command, "result": result, "feedback_score_share": share}
        atomic_write_text(json.dumps(data, indent=1), out.with_suffix(".json"))
    return 0
