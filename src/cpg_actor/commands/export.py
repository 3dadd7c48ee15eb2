"""`cpg-actor export`: a trained policy as one TorchScript or ONNX file (`cpg_actor.deploy`)."""

from __future__ import annotations

import argparse
from pathlib import Path

HELP = "export a trained policy (normaliser, networks, CPG step) as TorchScript or ONNX"
MAX_BATCH = 65_536  # robots per call: 16 times the GPU preset's envs; tracing allocates them


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("run_dir", help="a run directory written by `cpg-actor train`")
    parser.add_argument(
        "--format", default="onnx", choices=("onnx", "torchscript"), help="default onnx"
    )
    parser.add_argument(
        "--checkpoint", default=None, help="checkpoint file (default RUN_DIR/checkpoints/last.pt)"
    )
    parser.add_argument(
        "--out", default=None, help="output file (default RUN_DIR/export/policy.onnx or .pt)"
    )
    parser.add_argument(
        "--batch", type=int, default=1, help=f"robots per call, 1 to {MAX_BATCH:,} (default 1)"
    )
    parser.add_argument("--overwrite", action="store_true", help="replace an existing export")


def run(args: argparse.Namespace) -> int:
    from cpg_actor.config import TrainConfig, check_count
    from cpg_actor.deploy import load_policy
    from cpg_actor.deploy.export import SUFFIXES, export_policy, sidecar_paths
    from cpg_actor.files import check_path_given, refuse_linked_folders

    check_count(args.batch, "--batch", MAX_BATCH)
    for value, flag in ((args.run_dir, "RUN_DIR"), (args.checkpoint, "--checkpoint"),
                        (args.out, "--out")):  # fmt: skip
        check_path_given(value, flag)
    run_dir = Path(args.run_dir)
    if not run_dir.is_dir():
        raise FileNotFoundError(f"run directory {run_dir} does not exist")
    config_path = run_dir / "config.yaml"
    if not config_path.is_file():
        raise FileNotFoundError(
            f"{config_path} does not exist; is {run_dir} a training run directory?"
        )
    checkpoint = Path(args.checkpoint) if args.checkpoint else run_dir / "checkpoints" / "last.pt"
    out = Path(args.out) if args.out else run_dir / "export" / f"policy{SUFFIXES[args.format]}"
    if args.out is None:  # the run's own folder, never one a link there leads to
        refuse_linked_folders(run_dir / "export")
    if args.format == "onnx":
        try:
            import onnxscript  # noqa: F401  (torch.onnx.export needs it)
        except ImportError:
            raise ValueError(
                "ONNX export needs the onnx and onnxscript packages: "
                "pip install 'cpg-actor[export]' (or use --format torchscript)"
            ) from None
    # the run's agent, robot and env (as `cpg-actor eval`): the metadata describes that env
    policy = load_policy(checkpoint, run_config=TrainConfig.load(config_path))
    path = export_policy(policy, out, args.format, batch=args.batch, overwrite=args.overwrite)
    state = policy.agent.state_shape
    sidecars = sidecar_paths(path)
    where = "metadata_props" if args.format == "onnx" else "extra file metadata.json"
    print(
        f"exported {policy.config.agent} ({args.format}) to {path}: inputs observation "
        f"({args.batch}, {policy.actor_obs_dim}) and state ({args.batch}, "
        f"{', '.join(map(str, state))}), outputs action and next_state; metadata (joints, "
        f"control period, observation layout, actuator law) in its {where}; initial state in "
        f"{sidecars['initial_state'].name}, the robot's MJCF in {sidecars['mjcf'].name}"
    )
    return 0
