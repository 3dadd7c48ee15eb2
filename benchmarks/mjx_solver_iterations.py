"""MJX's Newton solver caps against each other and against MuJoCo's C solver, for both robots.

The hopper hops open loop for 3 s (the 2 Hz squat-and-extend pattern of ``tests/robots/
hopper/test_mjx.py``, 1 robot); the quadruped trots open loop for 6 s (the trot CPG at the drive of
a 1 m/s command, as ``tests/robots/anymal/test_anymal_mjx.py``, 4 robots, no reset noise). Each cap
setting (``mjx_iterations`` / ``mjx_ls_iterations``) runs the same actions; the script reports
the largest height difference from MJX at MuJoCo's own caps (100 / 50) and from MuJoCo's C
solver (float64, its defaults), the return against the C solver's, and the time of a control
step of the jitted step alone, as a ratio to the 15 / 15 caps measured in the same run
(rounds taken in turn, the fastest of each kept): for the hopper at ``--batch`` hoppers reset
with noise, each hopping at a phase of its own (MJX solves a batch until its slowest robot is
done), for the quadruped at its 4 robots.

    python benchmarks/mjx_solver_iterations.py [--caps 4/15 15/15 100/50] [--rounds 5]
        [--batch 64] [--output benchmarks/results/mjx_solver_iterations.md]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from bench_report import measured, write
from cpg_actor.robots.anymal import description as quadruped
from cpg_actor.robots.anymal.gaits import ANYMAL_GAITS
from cpg_actor.robots.anymal.mjx import MjxAnymalVectorEnv
from cpg_actor.robots.anymal.vector import AnymalVectorEnv
from cpg_actor.robots.hopper.mjx.dynamics import jax
from cpg_actor.robots.hopper.vector import make_vector_env

HOPPER_STEPS = 300  # 3 s at 100 Hz
ROBOTS = 4  # quadrupeds
QUADRUPED = {"command_range": (1.0, 1.0), "reset_noise": 0.0, "episode_seconds": 6.0,
             "tracking_sigma": 0.25}  # fmt: skip
TIMED_STEPS = 20  # control steps per timing round
BATCH_STEPS = 200  # control steps of the hopper batch compared across the caps (2 s)


def hop_action(k: int, offsets: np.ndarray | None = None) -> np.ndarray:
    """The tests' open-loop squat-and-extend pattern, 2 Hz, one row per phase offset (one
    robot at phase 0 by default)."""
    phase = 2 * np.pi * 2.0 * k * 0.01 + (np.zeros(1) if offsets is None else offsets)
    return np.stack([0.4 + 0.35 * np.sin(phase), -0.8 - 0.7 * np.sin(phase)], axis=1)


def trot_actions(steps: int) -> np.ndarray:
    """The open-loop trot preset at the drive of a 1 m/s command (as the quadruped's test)."""
    trot = ANYMAL_GAITS.open_loop_positions(
        "trot", 0.02, quadruped.NOMINAL_POSE, ROBOTS, steps, 1.0
    )
    return trot.numpy()


def hopper(caps: tuple[int, int] | None) -> dict:
    """Hip heights and rewards of the hopping run; ``caps`` None: MuJoCo's C solver."""
    overrides = {"reset_noise": 0.0, "episode_steps": 1000}
    if caps is None:
        env = make_vector_env(1, sim="mujoco", **overrides)
    else:
        env = make_vector_env(1, sim="mjx", mjx_iterations=caps[0], mjx_ls_iterations=caps[1],
                              **overrides)  # fmt: skip
    env.reset(seed=0)
    heights, rewards = [], []
    for k in range(HOPPER_STEPS):
        obs, reward = env.step(hop_action(k))[:2]
        heights.append(obs[:, 6])
        rewards.append(reward)
    return {"height": np.array(heights), "reward": np.array(rewards), "env": env}


def anymal(caps: tuple[int, int] | None, actions: list[np.ndarray]) -> dict:
    """Base heights, forward speeds and rewards of the trot; ``caps`` None: MuJoCo's C solver."""
    if caps is None:
        env = AnymalVectorEnv(ROBOTS, QUADRUPED)
    else:
        env = MjxAnymalVectorEnv(ROBOTS, {**QUADRUPED, "sim": "mjx", "mjx_iterations": caps[0],
                                          "mjx_ls_iterations": caps[1]})  # fmt: skip
    env.reset(seed=0)
    heights, speeds, rewards, falls = [], [], [], 0
    for action in actions:
        _, reward, terminated, _, info = env.step(action)
        heights.append(info["base_height"])
        speeds.append(info["forward_speed"])
        rewards.append(reward)
        falls += int(terminated.sum())
    return {"height": np.array(heights), "speed": np.array(speeds), "reward": np.array(rewards),
            "falls": falls, "env": env}  # fmt: skip


def hopper_batch(caps: tuple[int, int], batch: int) -> dict:
    """``batch`` hoppers (reset noise, phases of their own) hopping BATCH_STEPS steps: their
    hip heights and returns, and the env and actions to time from there."""
    env = make_vector_env(batch, sim="mjx", mjx_iterations=caps[0], mjx_ls_iterations=caps[1],
                          episode_steps=1000)  # fmt: skip
    env.reset(seed=0)
    offsets = np.random.default_rng(0).uniform(0.0, 2 * np.pi, batch)
    heights, rewards = [], []
    for k in range(BATCH_STEPS):
        obs, reward = env.step(hop_action(k, offsets))[:2]
        heights.append(obs[:, 6])
        rewards.append(reward)
    actions = [hop_action(BATCH_STEPS + k, offsets) for k in range(TIMED_STEPS)]
    return {"env": env, "actions": actions, "height": np.array(heights),
            "reward": np.array(rewards)}  # fmt: skip


def step_seconds(runs: dict, rounds: int) -> dict:
    """The fastest of ``rounds`` timings of TIMED_STEPS jitted steps per cap setting (in turn),
    per control step, from each run's state. (MJX's solver does not report its iterations:
    ``solver_niter`` stays 0.)"""
    best = {caps: np.inf for caps in runs}
    for _ in range(rounds):
        for caps, run in runs.items():
            env = run["env"]
            dynamics, state = env.dynamics, env.jax_state
            batch = [jax.device_put(np.asarray(a, np.float32)) for a in run["actions"]]
            jax.block_until_ready(batch)
            start = time.perf_counter()
            for action in batch:
                state, out = dynamics.step(state, action, env.episode)
            jax.block_until_ready((state, out))
            best[caps] = min(best[caps], (time.perf_counter() - start) / TIMED_STEPS)
    return best


def rows_for(name: str, runs: dict, reference: dict, seconds: dict, extra: str | None) -> list:
    base = runs.get((100, 50))
    fifteen = seconds.get((15, 15))
    rows = []
    for caps, run in runs.items():
        gap_c = np.abs(run["height"] - reference["height"]).max()
        gap_mjx = np.abs(run["height"] - base["height"]).max() if base is not None else np.nan
        ret, ret_c = run["reward"].sum(axis=0).mean(), reference["reward"].sum(axis=0).mean()
        cells = [
            name, f"{caps[0]} / {caps[1]}", f"{gap_mjx:.1e} m", f"{gap_c:.1e} m",
            f"{ret:.3f} / {ret_c:.3f} ({abs(ret / ret_c - 1):.3%})",
        ]  # fmt: skip
        if extra is not None:
            cells.append(f"{np.abs(run[extra] - reference[extra]).max():.1e} m/s")
        else:
            cells.append("")
        ratio = seconds[caps] / fifteen if fifteen else np.nan
        cells.append(f"{1e3 * seconds[caps]:.1f} ms ({ratio:.2f})")
        rows.append("| " + " | ".join(cells) + " |")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--caps", nargs="+", default=["4/15", "15/15", "100/50"],
                        help="mjx_iterations/mjx_ls_iterations settings")  # fmt: skip
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--batch", type=int, default=64, help="hoppers in the timed batch")
    parser.add_argument("--output", default="benchmarks/results/mjx_solver_iterations.md")
    args = parser.parse_args()
    settings = [tuple(int(x) for x in text.split("/")) for text in args.caps]

    hopper_c = hopper(None)
    hopper_runs = {caps: hopper(caps) for caps in settings}
    batches = {caps: hopper_batch(caps, args.batch) for caps in settings}
    hopper_seconds = step_seconds(batches, args.rounds)

    trot = trot_actions(int(QUADRUPED["episode_seconds"] / 0.02) - 1)  # no truncation
    anymal_c = anymal(None, trot)
    anymal_runs = {caps: anymal(caps, trot) for caps in settings}
    for run in anymal_runs.values():
        run["actions"] = trot[:TIMED_STEPS]
    anymal_seconds = step_seconds(anymal_runs, args.rounds)

    command = (f"python benchmarks/mjx_solver_iterations.py --caps {' '.join(args.caps)} "
               f"--batch {args.batch} --rounds {args.rounds}")  # fmt: skip
    falls = ", ".join(f"{c[0]} / {c[1]}: {r['falls']}" for c, r in anymal_runs.items())
    base = batches.get((100, 50))
    batch_rows = [
        f"| {c[0]} / {c[1]} | {np.abs(r['height'] - base['height']).max():.1e} m | "
        f"{np.abs(r['reward'].sum(0) / base['reward'].sum(0) - 1).max():.3%} |"
        for c, r in batches.items()
    ] if base is not None else []  # fmt: skip
    lines = [
        "# MJX's solver caps (iterations / line search) against MuJoCo's C solver",
        "",
        measured(command) + f", MJX on JAX's {jax.devices()[0].platform} backend (float32), "
        "MuJoCo in float64 with its defaults (100 / 50).",
        "",
        f"Hopper: 1 robot, {HOPPER_STEPS} control steps (3 s) of the 2 Hz hopping pattern, "
        f"hip height. Quadruped: {ROBOTS} robots, {len(trot)} control steps (6 s) of the "
        "open-loop trot at the drive of a 1 m/s command, base height and forward speed "
        f"(falls: C {anymal_c['falls']}; {falls}). Return: summed reward per robot, mean over "
        "robots. Step: one jitted control step of a batch alone, the fastest of "
        f"{args.rounds} rounds of {TIMED_STEPS} (ratio to 15 / 15): for the hopper a batch "
        f"of {args.batch} (reset noise, each at a phase of its own), for the quadruped its "
        f"{ROBOTS} robots.",
        "",
        "| robot | caps | height, largest difference from MJX 100 / 50 | from MuJoCo C | "
        "return, MJX / MuJoCo C | speed, largest difference from MuJoCo C | step |",
        "| --- | --- | ---: | ---: | ---: | ---: | ---: |",
        *rows_for("hopper", hopper_runs, hopper_c, hopper_seconds, None),
        *rows_for("quadruped", anymal_runs, anymal_c, anymal_seconds, "speed"),
        "",
        f"The timed hopper batch: {args.batch} hoppers, reset with noise (seed 0), each hopping "
        f"at a phase of its own for {BATCH_STEPS} control steps (2 s), against the same batch "
        "at MJX's 100 / 50 (MuJoCo's C solver draws other reset noise for the same seed):",
        "",
        "| caps | hip height, largest difference over the batch | return, largest relative "
        "difference over the batch |",
        "| --- | ---: | ---: |",
        *batch_rows,
        "",
    ]
    write(args.output, lines)


if __name__ == "__main__":
    main()
