"""``python -m cpg_actor.robots.hopper.demo``: drive the hopper open-loop and show what it does.

The desired positions follow a squat-and-extend sinusoid around the nominal pose,
``p_d = (0.4 + A sin(2 pi f t), -0.8 - 2A sin(2 pi f t))`` (knee twice the hip amplitude, in
anti-phase: the CPG preset's shape). The command prints the episode return with each reward
term (``--amplitude 0`` stands still: the reference the default weights are chosen against),
and can save a picture strip (``--image``, PNG) and a video (``--video``, MP4 or GIF).

Examples::

    python -m cpg_actor.robots.hopper.demo                                # return, 2 Hz, A = 0.3
    rad python -m cpg_actor.robots.hopper.demo --amplitude 0                  # standing still
    python -m cpg_actor.robots.hopper.demo --image docs/figures/hopper_mujoco.png --overwrite
    python -m cpg_actor.robots.hopper.demo --sim pybullet --video hop.mp4
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from cpg_actor.robots.common.video import write_video
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.env import HopperEnv
from cpg_actor.robots.hopper.reward import REWARD_TERMS


def desired_position(t: float, amplitude: float, frequency: float) -> np.ndarray:
    s = np.sin(2.0 * np.pi * frequency * t)
    return np.array([0.4 + amplitude * s, -0.8 - 2.0 * amplitude * s])


def run(args: argparse.Namespace) -> dict:
    config = HopperConfig(sim=args.sim, render_width=args.width, render_height=args.height)
    render = args.image is not None or args.video is not None
    env = HopperEnv(config, render_mode="rgb_array" if render else None)
    env.reset(seed=args.seed)
    steps = round(args.seconds / config.control_dt)
    period = round(1.0 / (args.frequency * config.control_dt)) if args.frequency > 0 else 1
    strip_steps = [min(steps - 1, steps // 2 + k * period // 4) for k in range(4)]
    totals = dict.fromkeys(REWARD_TERMS, 0.0)
    frames, strip, hip, foot = [], {}, [], []
    for i in range(steps):
        action = desired_position(i * config.control_dt, args.amplitude, args.frequency)
        _, _, terminated, _, info = env.step(action)
        for name in REWARD_TERMS:
            totals[name] += info["reward_terms"][name]
        hip.append(info["hip_height"])
        foot.append(info["foot_height"])
        if render:
            frame = env.render()
            if args.video is not None:
                frames.append(frame)
            if i in strip_steps:
                strip[i] = frame
        if terminated:
            break
    env.close()
    if args.image is not None:
        picture = np.concatenate([strip[i] for i in strip_steps if i in strip], axis=1)
        _write_image(picture, args.image, args.overwrite)
        print(f"wrote {args.image}")
    if args.video is not None:
        write_video(frames, args.video, fps=1.0 / config.control_dt, overwrite=args.overwrite)
        print(f"wrote {args.video}")
    return {
        "return": sum(totals.values()),
        "terms": totals,
        "hip": (min(hip), max(hip)),
        "foot_max": max(foot),
    }


def _write_image(image: np.ndarray, path: Path, overwrite: bool) -> None:
    import imageio.v2 as imageio

    if path.suffix.lower() != ".png":
        raise ValueError(f"--image must end in .png, got {path}")
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass --overwrite to replace it")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp.png")
    imageio.imwrite(tmp, image)
    tmp.replace(path)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m cpg_actor.robots.hopper.demo", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--sim", choices=("mujoco", "pybullet"), default="mujoco")
    parser.add_argument("--amplitude", type=float, default=0.3, help="HFE amplitude, rad")
    parser.add_argument("--frequency", type=float, default=2.0, help="Hz")
    parser.add_argument("--seconds", type=float, default=2.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--image", type=Path, help="PNG strip of 4 frames over one period")
    parser.add_argument("--video", type=Path, help="MP4 or GIF of the whole run")
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=320)
    parser.add_argument("--overwrite", action="store_true")
    args = parser.parse_args(argv)
    if args.seconds <= 0 or args.frequency < 0:
        parser.error("--seconds must be > 0 and --frequency >= 0")
    try:
        result = run(args)
    except (ValueError, FileExistsError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    terms = ", ".join(f"{k} {v:.2f}" for k, v in result["terms"].items())
    print(
        f"{args.sim}, {args.seconds:g} s, A = {args.amplitude:g} rad at {args.frequency:g} Hz: "
        f"return {result['return']:.2f} ({terms}); hip height {result['hip'][0]:.3f} to "
        f"{result['hip'][1]:.3f} m, foot up to {result['foot_max']:.3f} m"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
