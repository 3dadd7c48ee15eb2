"""The evaluation protocol's grid of commands as the evaluation during training: how well a
run tracks every command of :data:`~cpg_actor.robustness.protocol.GRID` on flat ground, asked
of it while it trains (``benchmarks/time_to_walk.py --grid``: the time to walk of the
omnidirectional task).

The grid and its rows are the protocol's (:func:`~cpg_actor.robustness.protocol.command_env`,
:func:`~cpg_actor.robustness.protocol.command_row`,
:func:`~cpg_actor.robustness.protocol.grid_means`), made cheap enough to run every few
iterations: no payload or push checks, no traces (no torque rate), ``episodes`` episodes per
command (1 by default) and, optionally, episodes shorter than the run's. Each command has envs
of its own, built once at the first evaluation and reset with the same seed every time, on the
nominal robot (:func:`~cpg_actor.training.evaluation.nominal_env`) and flat ground; the policy
takes its mean action. It draws no random numbers and touches neither the training envs nor
the normaliser, so a run trains the same with or without it (it plugs into the trainer's own
evaluation, :attr:`cpg_actor.training.evaluation.TrainingEvaluation.evaluator`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cpg_actor.robustness.protocol import GRID, command_env, command_row, flat_ground, grid_means


class GridEvaluation:
    """``evaluator(policy, seed)``: the grid's row of ``eval/*`` scalars for the run of
    ``config`` (its TrainConfig) on ``robot``: ``episodes`` deterministic episodes of
    ``episode_seconds`` (None: the run's) per command. The row: each protocol column the
    env reports, as its mean over the commands (``eval/lin_vel_error``, ``eval/fell``: the
    share of the episodes that fell, ...), ``eval/lin_vel_error_max`` (the worst command's),
    ``eval/fell_commands`` (how many commands had an episode fall) and the return and length
    over every episode (``eval/return``, ``eval/return_min``, ``eval/length``)."""

    def __init__(
        self, config: Any, robot: Any, episodes: int = 1, episode_seconds: float | None = None
    ) -> None:
        from cpg_actor.robustness.protocol import check_grid_robot
        from cpg_actor.training.evaluation import nominal_env

        if episodes < 1:
            raise ValueError(f"the grid evaluation needs episodes >= 1, got {episodes}")
        check_grid_robot(robot.name, config.env)
        base = nominal_env(config.env)
        changes = {} if episode_seconds is None else {"episode_seconds": episode_seconds}
        # checked now (a bad episode length is a ValueError here, not at the first evaluation)
        self.env_configs = [command_env(base, command, flat_ground(base), **changes)
                            for command in GRID]  # fmt: skip
        self.config, self.robot, self.episodes = config, robot, episodes
        self.envs: list[Any] = []

    @property
    def episode_seconds(self) -> float:
        return float(self.env_configs[0].episode_seconds)

    def __call__(self, policy, seed: int) -> dict[str, float]:
        from cpg_actor.training.build import make_env
        from cpg_actor.training.evaluation import evaluate

        if not self.envs:
            self.envs = [make_env(self.config, self.robot, self.episodes, self.config.env_threads,
                                  env_config) for env_config in self.env_configs]  # fmt: skip
        rows, returns, lengths = [], [], []
        for command, env, env_config in zip(GRID, self.envs, self.env_configs, strict=True):
            result = evaluate(policy, env, seed=seed, control_dt=float(env_config.control_dt),
                              max_steps=env_config.episode_steps, traces=False)  # fmt: skip
            rows.append(command_row(command, result))
            returns.append(result["episode_return"])
            lengths.append(result["length"])
            reported = {str(name) for name in result["metric_names"]}
        row = {f"eval/{key}": value for key, value in grid_means(rows).items() if key in reported}
        errors = [r["lin_vel_error"] for r in rows]
        row["eval/lin_vel_error_max"] = float(np.max(errors))  # NaN if any is
        row["eval/fell_commands"] = float(sum(r["fell"] > 0 for r in rows))
        returns, lengths = np.concatenate(returns), np.concatenate(lengths)
        row.update({"eval/return": float(returns.mean()), "eval/return_min": float(returns.min()),
                    "eval/length": float(lengths.mean())})  # fmt: skip
        return row

    def close(self) -> None:
        for env in self.envs:
            env.close()
        self.envs = []
