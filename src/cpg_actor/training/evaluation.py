"""Deterministic evaluation: every env runs one episode with the policy's mean action.

Used by ``cpg-actor eval`` (traces, figures) and by the runner's evaluation during training
(``eval_interval``), which runs it on environments of its own: it never steps the training
envs, never updates the observation normaliser and draws no random numbers (the mean action
is taken and the envs are reset with their own seed), so training is the same with or
without it.

On an env with a tensor face (MJX: :class:`cpg_actor.robots.common.torch_env.TensorEnv`) an
evaluation without traces stays on the env's device: the policy's tensors go to the env and its
returns, lengths and episode metrics are summed there, with a look at the host only every
:data:`CHECK_EVERY` steps (whether every episode has ended) instead of copying each step's
outputs to numpy. The numbers are those of the numpy loop (tested).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import torch

from cpg_actor.robots.common.torch_env import TensorEnv
from cpg_actor.training.seeding import EVAL_SEED_KEY, derived_seed


def nominal_env(env_config):
    """``env_config`` without its randomised training's ranges (``env.randomize``), as
    legged_gym's play does: a policy trained on random robots is evaluated on the nominal one
    (``cpg-actor eval``, the transfer study, the robustness suite). Its other fields, a fixed
    perturbation included, are kept."""
    randomize = getattr(env_config, "randomize", None)
    if randomize is None or not randomize.active:
        return env_config
    return env_config.replace(randomize=type(randomize)())


def finite_mean(values) -> float:
    """The mean of the finite values; NaN (and no warning) when there is none, as for a
    metric no episode defined (the quadruped's cost of transport of robots that did not walk)."""
    values = np.asarray(values, dtype=np.float64)
    finite = values[np.isfinite(values)]
    return float(finite.mean()) if finite.size else float("nan")


def observation_columns(robot) -> dict[str, list[int]]:
    """Where the traces' quantities are in the observation, by the names the env's
    :class:`cpg_actor.robots.spec.RobotSpec` gives its columns: measured joint positions
    (``p_m_<joint>``) and velocities (``v_m_<joint>``) in joint order, and each observation
    the robot traces on its own (``traced_observations``: the hopper's ``hip_height``). A
    quantity the robot does not observe is left out."""
    names = list(robot.observation_names)
    columns = {}
    for key, prefix in (("measured_position", "p_m_"), ("measured_velocity", "v_m_")):
        wanted = [prefix + joint for joint in robot.joint_names]
        if all(name in names for name in wanted):
            columns[key] = [names.index(name) for name in wanted]
    for name in robot.traced_observations:
        columns[name] = [names.index(name)]
    return columns


# control steps between the device loop's looks at the host (has every episode ended?): a
# divisor of the usual episode lengths (500 hopper steps, 1,000 quadruped steps), so that
# the loop stops at the step the last episode ends
CHECK_EVERY = 50

# the step info an env may report -> its trace: feet on the ground (E, feet) as 1 or 0, the
# base's forward speed (m/s), the velocity command (E, 3: forward, lateral, yaw), under a
# perturbation's push 1 at the step it came, and the physical metrics' inputs
# (:mod:`cpg_actor.metrics.physical`): the joint torques (E, J; N m), the feet's positions
# in the world (E, feet, 3; m) and the joints' true positions and velocities (E, J; rad,
# rad/s: what the robot did, without the sensor noise a perturbation adds to the observation)
TRACED_INFO = {"contact": "foot_contact", "forward_speed": "base_forward_speed",
               "command": "command", "pushed": "push", "joint_torque": "joint_torque",
               "foot_position": "foot_position", "measured_position": "joint_position",
               "measured_velocity": "joint_velocity"}  # fmt: skip


@torch.no_grad()
def evaluate(
    policy,
    env,
    seed: int,
    control_dt: float,
    max_steps: int,
    traces: bool = True,
    on_device: bool | None = None,
) -> dict[str, np.ndarray]:
    """Run every env of ``env`` to the end of its first episode with the mean action.

    ``policy`` is a :class:`cpg_actor.training.policy.Policy` (or anything with its ``reset`` and
    ``act``); its recurrent state is reset here, its normaliser is not updated. Returns
    ``episode_return`` and ``length`` per env, the env's episode metrics (its
    ``info["episode_metrics"]``: ``hop_height`` for the hopper) per env, their names in
    ``metric_names`` and, with ``traces``, per-step traces ``(T, E, ...)`` (rows after an env's
    episode ended are NaN), with ``foot_contact``, ``base_forward_speed`` and ``command`` where
    the env's step info has them (``TRACED_INFO``; the columns of ``foot_contact`` are named
    in ``foot_names``). ``desired_position`` is the command the env tracked (after its clip
    to the joint limits, ``action_low`` / ``action_high``, saved too) and
    ``desired_velocity`` its finite difference over ``control_dt``, for every agent alike
    (NaN at the first step); a CPG's output ``x`` and analytic ``x_dot`` are ``cpg_position``
    and ``cpg_velocity``.

    ``on_device``: run on the env's tensor face without per-step copies to the host (module
    docstring); None: when the env has one and no traces are asked for.
    """
    if on_device is None:
        on_device = not traces and isinstance(env, TensorEnv)
    if on_device:
        if traces:
            raise ValueError("traces are recorded on the host: evaluate(on_device=False)")
        length, returns, metrics, standing = _run_on_device(policy, env, seed, max_steps)
        return _result(env, {}, length, returns, metrics, standing, control_dt, traces)
    num_envs = env.num_envs
    columns = observation_columns(env.robot)
    obs, _ = env.reset(seed=seed)
    obs = np.asarray(obs, dtype=np.float32)
    standing = {name: float(obs[:, columns[name][0]].mean())
                for name in env.robot.traced_observations}  # fmt: skip
    policy.reset(num_envs)
    # the desired velocity of the first step is left out (NaN): the command before it is the
    # env's reset pose, not the agent's
    previous_desired = None
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
                step.agent.extras, info, desired, previous_desired, measured, columns, reward,
                control_dt,
            )  # fmt: skip
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
    return _result(env, records, length, returns, metrics, standing, control_dt, traces)


def evaluate_policy(policy, config, episodes: int, seed: int) -> dict[str, np.ndarray]:
    """:func:`evaluate` on ``episodes`` envs of the agent's own environment, built from the
    run's ``config`` (``cpg-actor eval``, the transfer study): traces ``(T, E, ...)`` (rows
    after an env's episode ended are NaN), with the agent's name, the motor's speed limit and
    the CPG's oscillator names."""
    from cpg_actor.robots.registry import get_robot
    from cpg_actor.training.build import make_env

    env = make_env(config, get_robot(config.robot), episodes, config.env_threads)
    try:
        traces = evaluate(
            policy,
            env,
            seed=seed,
            control_dt=float(config.env.control_dt),
            max_steps=config.env.episode_steps,
        )
    finally:
        env.close()
    traces["agent"] = np.array(config.agent)
    # the motor's no-load speed (rad/s), drawn on the velocity panels of traces.png: one number,
    # or one per joint of a leg (the Go1's)
    traces["velocity_limit"] = np.asarray(config.env.velocity_limit, dtype=float)
    cpg = getattr(policy.agent, "cpg", None)  # a CPG in the agent: its oscillators' names
    if cpg is not None and "theta_dot" in traces:
        traces["oscillator_names"] = np.array(cpg.topology.names, dtype=str)
    return traces


def _run_on_device(policy, env, seed: int, max_steps: int):
    """The loop of :func:`evaluate` on the env's tensor face: ``(length, episode_return,
    metrics, standing values of the traced observations)`` as numpy, the same numbers as the
    numpy loop's."""
    columns = observation_columns(env.robot)
    obs, _ = env.reset_tensors(seed)
    device, num_envs = obs.device, env.num_envs
    # averaged as the numpy loop does
    standing = {name: obs[:, columns[name][0]].clone() for name in env.robot.traced_observations}
    policy.reset(num_envs)
    active = torch.ones(num_envs, dtype=torch.bool, device=device)
    length = torch.zeros(num_envs, dtype=torch.int64, device=device)
    returns = torch.zeros(num_envs, dtype=torch.float64, device=device)
    finite = torch.ones((), dtype=torch.bool, device=device)
    metrics: dict[str, torch.Tensor] = {}
    for step in range(max_steps + 1):
        action = policy.act(obs, deterministic=True, tensor_action=True).action
        finite &= torch.isfinite(action).all()  # checked at the end: no wait per step
        out = env.step_tensors(action, check_finite=False)
        done = out.terminated | out.truncated
        returns += torch.where(active, out.reward.to(torch.float64), 0.0)
        ended = active & done
        for name, values in out.episode_metrics.items():
            metric = metrics.get(name)
            if metric is None:
                metric = torch.full((num_envs,), torch.nan, dtype=torch.float64, device=device)
            metrics[name] = torch.where(ended, values.to(torch.float64), metric)
        length += active
        active &= ~done
        obs = out.obs
        if (step + 1) % CHECK_EVERY == 0 and not bool(active.any()):
            break
    if not bool(finite):
        raise ValueError("the policy's actions became NaN or inf: actions must be finite")
    return (
        length.cpu().numpy(),
        returns.cpu().numpy(),
        {name: value.cpu().numpy() for name, value in metrics.items()},
        {name: float(value.cpu().numpy().mean()) for name, value in standing.items()},
    )


def _result(env, records, length, returns, metrics, standing, control_dt, traces):
    """:func:`evaluate`'s result from its loop's numbers (the traces ``records``)."""
    result = {key: np.stack(values) for key, values in records.items()}
    if traces:
        result["time"] = control_dt * np.arange(1, len(records["reward"]) + 1)
    result["length"] = length
    result["episode_return"] = returns
    result.update(metrics)
    result["metric_names"] = np.array(sorted(metrics), dtype=str)
    result["joint_names"] = np.array(env.robot.joint_names, dtype=str)
    # the action space the desired positions were clipped to (the joint limits, rad)
    result["action_low"] = np.asarray(env.robot.action_low, dtype=np.float64)
    result["action_high"] = np.asarray(env.robot.action_high, dtype=np.float64)
    if "foot_contact" in result:  # the columns of foot_contact
        feet = getattr(getattr(env, "unwrapped", env), "foot_names", None)
        if feet is None:
            feet = [f"foot {i}" for i in range(result["foot_contact"].shape[-1])]
        result["foot_names"] = np.array(feet, dtype=str)
    for name, value in standing.items():  # each traced observation's mean after reset
        result[f"standing_{name}"] = np.array(value)
    result["control_dt"] = np.array(control_dt)
    return result


def _trace_row(
    extras, info, desired, previous_desired, measured, columns, reward, dt
) -> dict[str, Any]:
    # the desired positions the robot tracked, as the env reports them: the action clipped to
    # the joint limits for agents acting on joint positions, the nominal pose + the CPG's
    # output, clipped, for agents whose env holds the CPG (cho2019); an env that does not
    # report them gets the policy's action (already clipped to the action space)
    applied = np.asarray(info.get("desired_position", desired), dtype=np.float64)
    num_envs = applied.shape[0]
    row = {"desired_position": applied}
    for key, where in columns.items():
        joints = key in ("measured_position", "measured_velocity")
        row[key] = measured[:, where] if joints else measured[:, where[0]]
    for key in ("measured_position", "measured_velocity"):  # not observed as such
        if key not in row and key in info:
            row[key] = np.asarray(info[key], dtype=np.float64)
    row["foot_height"] = np.asarray(info.get("foot_height", np.full(num_envs, np.nan)))
    row["reward"] = np.asarray(reward, dtype=np.float64)
    # one definition for every agent: the finite difference of the desired positions sent
    # over the control period (a CPG's analytic x_dot ignores the clip and, for a foot-space
    # pattern, is not a joint velocity at all); kept apart as cpg_velocity
    if previous_desired is None:
        row["desired_velocity"] = np.full_like(applied, np.nan)
    else:
        row["desired_velocity"] = (applied - previous_desired) / dt
    if "desired_velocity" in extras:
        row["cpg_velocity"] = extras["desired_velocity"].cpu().numpy()
    elif "desired_velocity" in info:  # CPG inside the environment
        row["cpg_velocity"] = np.asarray(info["desired_velocity"])
    for key in ("theta_dot", "r_ddot", "xi", "kappa", "cpg_parameters", "cpg_position"):
        if key in extras:
            row[key] = extras[key].cpu().numpy()
        elif key in info:
            row[key] = np.asarray(info[key])
    # a legged robot's gait and speed tracking (the quadruped's info); renamed where the name
    # is also an episode metric's (the mean forward speed)
    for key, trace in TRACED_INFO.items():
        if key in info:
            row[trace] = np.asarray(info[key])
    return row


def evaluation_row(
    policy, env, seed: int, control_dt: float, max_steps: int, traced_metrics=None
) -> dict[str, float]:
    """The metrics row of one evaluation during training (both runners' ``eval/*``): the mean
    and worst return, the mean length and the mean of each of the env's own metrics.

    ``traced_metrics``: a function of the traces giving per-episode metrics (e.g.
    :func:`cpg_actor.metrics.physical.episode_metrics`: the hopper's ``eval/hop_apex``,
    ...); the episodes are then traced and its metrics added, the mean over the episodes that
    define them. None by default: traces cost each evaluation a copy of every step to the host
    (the time-to-quality benchmark asks for them)."""
    traced = traced_metrics is not None
    result = evaluate(policy, env, seed=seed, control_dt=control_dt, max_steps=max_steps,
                      traces=traced)  # fmt: skip
    row = {
        "eval/return": float(result["episode_return"].mean()),
        "eval/return_min": float(result["episode_return"].min()),
        "eval/length": float(result["length"].mean()),
    }
    for name in result["metric_names"]:  # the env's own (the hopper's hop height)
        row[f"eval/{name}"] = finite_mean(result[str(name)])
    if traced:
        for name, values in traced_metrics(result).items():
            row[f"eval/{name}"] = finite_mean(values)
    return row


def evaluation_env(config: Any, robot: Any) -> Any:
    """The envs a run is evaluated on during training: ``config.eval_episodes`` of the run's
    robot's, on its env config without training randomisation (:func:`nominal_env`)."""
    from cpg_actor.training.build import make_env

    return make_env(
        config, robot, config.eval_episodes, config.env_threads, nominal_env(config.env)
    )


class TrainingEvaluation:
    """The evaluation during training, of both runners: one episode with the mean action on
    each of ``config.eval_episodes`` envs of its own (the run's ``robot``'s, built at the first
    evaluation; ``env`` replaces them), always reset with the run's evaluation seed, by a
    policy of its own around the run's agent and normaliser (the training envs' CPG states
    stay untouched). ``traced_metrics``: each evaluation also gives these metrics of its
    traces (:func:`evaluation_row`); None unless a caller sets it. ``evaluator``: a caller's
    own evaluation instead of those episodes, ``evaluator(policy, seed)`` giving the row
    (``eval/*`` scalars) for the same policy and seed, on envs of its own and drawing no
    random numbers (the time-to-walk benchmark's grid of commands,
    :class:`cpg_actor.robustness.grid_evaluation.GridEvaluation`), closed with this one if
    it has ``close``; None unless a caller sets it (then the run's envs are never built)."""

    def __init__(
        self, config: Any, robot: Any, agent, normalizer, action_low, action_high, env: Any = None
    ) -> None:
        self.traced_metrics = None
        self.evaluator: Any = None
        self.config = config
        self.robot = robot
        self.agent, self.normalizer = agent, normalizer
        self.action_low, self.action_high = action_low, action_high
        self.env = env

    def __call__(self) -> dict[str, float]:
        """``eval/return``, ``eval/return_min``, ``eval/length``, ``eval/<metric>`` and the
        seconds it took, ``time/eval``."""
        from cpg_actor.training.policy import Policy

        cfg = self.config
        start = time.perf_counter()
        policy = Policy(
            self.agent,
            self.normalizer,
            self.action_low,
            self.action_high,
            cfg.ppo.normalize_observations,
        )
        seed = derived_seed(cfg.seed, EVAL_SEED_KEY)
        if self.evaluator is not None:
            row = dict(self.evaluator(policy, seed))
        else:
            if self.env is None:
                self.env = evaluation_env(cfg, self.robot)
            row = evaluation_row(
                policy,
                self.env,
                seed=seed,
                control_dt=float(cfg.env.control_dt),
                max_steps=cfg.env.episode_steps,
                traced_metrics=self.traced_metrics,
            )
        row["time/eval"] = time.perf_counter() - start
        return row

    def close(self) -> None:
        close = getattr(self.evaluator, "close", None)
        if close is not None:
            close()
        if self.env is not None:
            self.env.close()
            self.env = None
