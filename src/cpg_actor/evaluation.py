"""Deterministic evaluation: every env runs one episode with the policy's mean action.

Used by ``cpg-actor eval`` (traces, figures) and by the runner's evaluation during training
(``eval_interval``), which runs it on environments of its own: it never steps the training
envs, never updates the observation normaliser and draws no random numbers (the mean action
is taken and the envs are reset with their own seed), so training is the same with or
without it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

HIP_HEIGHT = 6  # index of the hip height in the hopper observation


@torch.no_grad()
def evaluate(
    policy,
    env,
    seed: int,
    control_dt: float,
    max_steps: int,
    traces: bool = True,
) -> dict[str, np.ndarray]:
    """Run every env of ``env`` to the end of its first episode with the mean action.

    ``policy`` is a :class:`cpg_actor.policy.Policy` (or anything with its ``reset`` and
    ``act``); its recurrent state is reset here, its normaliser is not updated. Returns
    ``episode_return`` and ``length`` per env, the env's episode metrics (its
    ``info["episode_metrics"]``: ``hop_height`` for the hopper) per env, their names in
    ``metric_names`` and, with ``traces``, per-step traces ``(T, E, ...)`` (rows after an env's
    episode ended are NaN).
    """
    num_envs = env.num_envs
    obs, _ = env.reset(seed=seed)
    obs = np.asarray(obs, dtype=np.float32)
    standing = float(obs[:, HIP_HEIGHT].mean())
    policy.reset(num_envs)
    previous_desired = obs[:, 4:6].copy()
    active = np.ones(num_envs, dtype=bool)
    length = np.zeros(num_envs, dtype=np.int64)
    returns = np.zeros(num_envs)
    metrics: dict[str, np.ndarray] = {}  # the env's per-episode metrics (hop_height)
    records: dict[str, list[np.ndarray]] = {}
    for _ in range(max_steps + 1):
        step = policy.act(obs, deterministic=True)
        desired = step.action
        next_obs, reward, terminated, truncated, info = env.step(desired)
        done = np.logical_or(terminated, truncated)
        measured = np.asarray(next_obs, dtype=np.float32).copy()
        if done.any():
            measured[done] = np.asarray(info["final_obs"], dtype=np.float32)[done]
        returns += np.where(active, np.asarray(reward, dtype=np.float64), 0.0)
        for name, values in info.get("episode_metrics", {}).items():
            metric = metrics.setdefault(name, np.full(num_envs, np.nan))
            ended = active & done
            metric[ended] = np.asarray(values)[ended]
        if traces:
            row = _trace_row(
                step.agent.extras, info, desired, previous_desired, measured, reward, control_dt
            )
            for key, value in row.items():
                value = np.asarray(value, dtype=np.float64).copy()
                value[~active] = np.nan
                records.setdefault(key, []).append(value)
            previous_desired = row["desired_position"]
        length += active
        active &= ~done
        obs = np.asarray(next_obs, dtype=np.float32)
        if not active.any():
            break
    result = {key: np.stack(values) for key, values in records.items()}
    if traces:
        result["time"] = control_dt * np.arange(1, len(records["reward"]) + 1)
    result["length"] = length
    result["episode_return"] = returns
    result.update(metrics)
    result["metric_names"] = np.array(sorted(metrics), dtype=str)
    result["standing_hip_height"] = np.array(standing)
    result["control_dt"] = np.array(control_dt)
    return result


def _trace_row(extras, info, desired, previous_desired, measured, reward, dt) -> dict[str, Any]:
    # the desired positions the hopper tracked: the clipped action for agents acting on joint
    # positions, the CPG's output for agents whose env holds the CPG (cho2019)
    applied = np.asarray(info.get("desired_position", desired), dtype=np.float64)
    num_envs = applied.shape[0]
    row = {
        "desired_position": applied,
        "measured_position": measured[:, 0:2],
        "measured_velocity": measured[:, 2:4],
        "hip_height": measured[:, HIP_HEIGHT],
        "foot_height": np.asarray(info.get("foot_height", np.full(num_envs, np.nan))),
        "reward": np.asarray(reward, dtype=np.float64),
    }
    if "desired_velocity" in extras:
        row["desired_velocity"] = extras["desired_velocity"].cpu().numpy()
    elif "desired_velocity" in info:  # CPG inside the environment
        row["desired_velocity"] = np.asarray(info["desired_velocity"])
    else:  # the MLP has no analytic velocity: finite difference of its desired positions
        row["desired_velocity"] = (applied - previous_desired) / dt
    for key in ("theta_dot", "r_ddot", "xi", "kappa", "cpg_parameters"):
        if key in extras:
            row[key] = extras[key].cpu().numpy()
        elif key in info:
            row[key] = np.asarray(info[key])
    return row
