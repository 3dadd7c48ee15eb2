"""How closely the MJX hopper follows the MuJoCo CPU backend, measured on the checks of
``tests/robots/hopper/test_mjx.py`` (which assert looser tolerances): free fall against the hand
calculation, standing statics, 3 s of open-loop hopping, its reward terms and apex payments.

    python benchmarks/mjx_agreement.py [--set mjx_iterations=100 ...]
        [--output benchmarks/results/mjx_agreement.md]
"""

from __future__ import annotations

import argparse

import numpy as np

from bench_report import measured, write
from cpg_actor.config import parse_override
from cpg_actor.robots.hopper import description as robot
from cpg_actor.robots.hopper import kinematics
from cpg_actor.robots.hopper.mjx.dynamics import jax
from cpg_actor.robots.hopper.vector import make_vector_env

HOLD = np.array(robot.NOMINAL_POSE)
TERMS = ("r1", "r2", "r3", "r4", "r5")


def hop_action(k: int) -> np.ndarray:
    """The tests' open-loop squat-and-extend pattern, 2 Hz."""
    phase = 2 * np.pi * 2.0 * k * 0.01
    return np.array([[0.4 + 0.35 * np.sin(phase), -0.8 - 0.7 * np.sin(phase)]])


def pair(extra: dict, **overrides):
    mjx = make_vector_env(1, sim="mjx", **extra, **overrides)
    cpu = make_vector_env(1, sim="mujoco", **overrides)
    mjx.reset(seed=0)
    cpu.reset(seed=0)
    return mjx, cpu


def measure(extra: dict) -> list[tuple[str, str]]:
    rows = []
    env, cpu = pair(extra, reset_noise=0.0, reset_clearance=0.1)
    start = kinematics.standing_hip_height(HOLD) + 0.1
    fall = gap = 0.0
    for step in range(1, 11):
        obs, cpu_obs = env.step(HOLD[None])[0], cpu.step(HOLD[None])[0]
        n = 10 * step
        fall = max(fall, abs(obs[0, 6] - (start - robot.GRAVITY * 1e-6 * n * (n + 1) / 2)))
        gap = max(gap, float(np.abs(obs - cpu_obs).max()))
    rows.append(("free fall, 0.1 s: hip height against the hand calculation", f"{fall:.1e} m"))
    rows.append(("free fall: largest observation difference from MuJoCo", f"{gap:.1e}"))

    env, cpu = pair(extra, reset_noise=0.0)
    for _ in range(100):
        obs, cpu_obs = env.step(HOLD[None])[0], cpu.step(HOLD[None])[0]
    rows.append(("standing 1 s: hip height difference", f"{abs(obs[0, 6] - cpu_obs[0, 6]):.1e} m"))

    env, cpu = pair(extra, reset_noise=0.0, episode_steps=1000)
    sums = {name: np.zeros(2) for name in TERMS}
    hip = 0.0
    for k in range(300):
        obs, _, _, _, info = env.step(hop_action(k))
        cpu_obs, _, _, _, cpu_info = cpu.step(hop_action(k))
        hip = max(hip, abs(float(obs[0, 6] - cpu_obs[0, 6])))
        for name in TERMS:
            sums[name] += (info["reward_terms"][name][0], cpu_info["reward_terms"][name][0])
    rows.append(("3 s of open-loop hopping: largest hip height difference", f"{hip:.1e} m"))
    for name, (a, b) in sums.items():
        rows.append((f"  {name} summed: MJX / MuJoCo", f"{a:.3f} / {b:.3f} ({abs(a / b - 1):.2%})"))

    env, cpu = pair(extra, reset_noise=0.0, episode_steps=1000, hop_reward="apex")
    paid, payments = np.zeros(2), np.zeros(2)
    for k in range(200):
        a = env.step(hop_action(k))[4]["reward_terms"]["r1"][0]
        b = cpu.step(hop_action(k))[4]["reward_terms"]["r1"][0]
        paid += (a, b)
        payments += (a > 0, b > 0)
    rows.append((
        "apex reward over 2 s: payments, sum (MJX / MuJoCo)",
        f"{payments[0]:.0f} / {payments[1]:.0f}, {paid[0]:.4f} / {paid[1]:.4f}",
    ))  # fmt: skip
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--set", dest="overrides", action="append", default=[],
        help="an env setting of the MJX side, e.g. mjx_iterations=100 (repeatable)",
    )  # fmt: skip
    parser.add_argument("--output", default="benchmarks/results/mjx_agreement.md")
    args = parser.parse_args()
    extra = {}
    for text in args.overrides:
        extra.update(parse_override(text))
    rows = measure(extra)
    command = "python benchmarks/mjx_agreement.py" + "".join(f" --set {t}" for t in args.overrides)
    lines = [
        "# MJX against MuJoCo (CPU)",
        "",
        measured(command) + f", MJX on JAX's {jax.devices()[0].platform} backend (float32), "
        "MuJoCo in float64.",
        "",
        "| check | measured |",
        "| --- | --- |",
        *(f"| {name} | {value} |" for name, value in rows),
        "",
    ]
    write(args.output, lines)


if __name__ == "__main__":
    main()
