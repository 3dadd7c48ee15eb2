"""What the evaluation traces hold for the report: the desired positions sent to the env (after
its clip to the joint limits) and, for every agent alike, their finite difference over the
control period as the desired velocity; the action space's bounds for the time at a stop."""

from types import SimpleNamespace

import numpy as np
import pytest

from cpg_actor.metrics import signals
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.training.evaluation import evaluate
from cpg_actor_studies.reproduction.results import sent_velocity


class ScriptedPolicy:
    """The same scripted action for every env, with no extras (as the MLP actor)."""

    def __init__(self, actions):
        self.actions = np.asarray(actions, dtype=np.float32)
        self.step = 0

    def reset(self, num_envs):
        self.num_envs, self.step = num_envs, 0

    def act(self, obs, deterministic=True):
        action = self.actions[min(self.step, len(self.actions) - 1)]
        self.step += 1
        return SimpleNamespace(
            action=np.tile(action, (self.num_envs, 1)), agent=SimpleNamespace(extras={})
        )


def test_joint_commands_are_traced_as_sent_and_differenced_by_hand():
    from cpg_actor.robots.hopper.vector import make_vector_env

    config = HopperConfig(episode_steps=4)
    # HFE beyond its upper limit (1.3 rad) for two steps: the env tracks 1.3
    script = [[0.4, -0.8], [2.0, -0.9], [2.5, -1.0], [0.5, -0.6]]
    env = make_vector_env(2, config=config, num_threads=1)
    try:
        traces = evaluate(ScriptedPolicy(script), env, seed=0, control_dt=0.01, max_steps=4)
    finally:
        env.close()
    sent = traces["desired_position"][:, 0]
    assert sent == pytest.approx(np.array([[0.4, -0.8], [1.3, -0.9], [1.3, -1.0], [0.5, -0.6]]))
    velocity = traces["desired_velocity"][:, 0]
    assert np.isnan(velocity[0]).all()  # the first step: no previous command of the agent's
    # by hand: (1.3 - 0.4) / 0.01, (-0.9 + 0.8) / 0.01; then 0 (clipped!) and -10; then -80, 40
    expected = np.array([[90.0, -10.0], [0.0, -10.0], [-80.0, 40.0]])
    assert velocity[1:] == pytest.approx(expected, abs=1e-4)
    assert "cpg_velocity" not in traces  # no CPG here
    assert traces["action_low"] == pytest.approx([-0.5, -1.7])
    assert traces["action_high"] == pytest.approx([1.3, 0.1])
    # the report computes the same from the positions, and the time at a stop from the bounds
    assert np.allclose(sent_velocity(traces), traces["desired_velocity"], equal_nan=True)
    share = signals.joint_stop_share(traces["desired_position"], traces["action_low"],
                               traces["action_high"])  # fmt: skip
    assert share == pytest.approx(2 / 4)


def test_cho2019_traces_hold_the_clipped_nominal_pose_plus_x_and_its_difference():
    from cpg_actor.robots.hopper.cho2019 import CPGParameterVectorEnv

    config = HopperConfig(episode_steps=30)
    env = CPGParameterVectorEnv(2, config, num_threads=1)
    nominal = np.asarray(env.robot.nominal_pose)
    low, high = np.asarray(env.robot.action_low), np.asarray(env.robot.action_high)
    try:
        # the largest amplitudes (Cho et al.'s ranges keep nominal + x within the limits)
        script = [[0.0, 0.0, 1.0, 1.0, 0.0]]
        traces = evaluate(ScriptedPolicy(script), env, seed=0, control_dt=0.01, max_steps=30)
    finally:
        env.close()
    sent = traces["desired_position"]
    assert sent == pytest.approx(np.clip(nominal + traces["cpg_position"], low, high), abs=1e-6)
    velocity = traces["desired_velocity"]
    assert np.isnan(velocity[0]).all()
    assert velocity[1:] == pytest.approx(np.diff(sent, axis=0) / 0.01, abs=1e-6)
    assert "cpg_velocity" in traces and traces["cpg_velocity"].shape == sent.shape
