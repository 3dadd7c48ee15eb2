"""The CPG-inside-the-environment wrapper of the Cho et al. 2019 baseline."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from cpg_actor.robots.hopper.cho2019 import (
    PARAMETER_RANGES,
    CPGParameterVectorEnv,
    action_to_parameters,
    parameters_to_action,
)
from cpg_actor.robots.hopper.cho2019_reference import REFERENCE_PARAMETERS, evaluate_parameters
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.cpg import HOPPER_NOMINAL_POSE, hopper_cpg

SHORT = HopperConfig(episode_steps=20)


def test_wrapper_output_equals_the_standalone_cpg_module():
    nu, rho_h, rho_k, phi = 1.7, 0.25, 0.5, 0.6
    params = np.array([[nu, nu, rho_h, rho_k, phi], [2.2, 2.2, 0.1, 0.3, -1.0]])
    env = CPGParameterVectorEnv(2, config=SHORT)
    env.reset(seed=3)
    actions = parameters_to_action(params)
    reference = hopper_cpg(
        SHORT.control_dt,
        initial={
            "frequency": nu,
            "amplitude": (rho_h, rho_k),
            "phase_bias": ((0.0, phi), (-phi, 0.0)),
        },
        dtype=torch.float64,
    )
    state = reference.initial_state(1)
    for _ in range(15):
        _, _, _, _, info = env.step(actions)
        with torch.no_grad():
            output, state = reference(state)
        np.testing.assert_allclose(info["cpg_position"][0], output.position[0].numpy(), atol=1e-12)
        np.testing.assert_allclose(
            info["desired_velocity"][0], output.velocity[0].numpy(), atol=1e-12
        )
        np.testing.assert_allclose(
            info["desired_position"][0],
            np.asarray(HOPPER_NOMINAL_POSE) + output.position[0].numpy(),
            atol=1e-6,  # the hopper keeps desired positions in float32
        )
        np.testing.assert_allclose(info["cpg_parameters"], params, atol=1e-12)
    env.close()


def test_observation_carries_the_cpg_state():
    env = CPGParameterVectorEnv(1, config=SHORT)
    obs, _ = env.reset(seed=0)
    assert obs.shape == (1, 16) and obs.dtype == np.float32
    np.testing.assert_allclose(obs[0, 8:10], [1.0, -1.0], atol=1e-6)  # cos of (0, pi)
    obs, *_ = env.step(np.zeros((1, 5)))
    state = env.state
    np.testing.assert_allclose(obs[0, 8:10], torch.cos(state.phase[0]).numpy(), rtol=1e-6)
    np.testing.assert_allclose(obs[0, 12:14], state.amplitude[0].numpy(), rtol=1e-6)
    assert env.observation_space.contains(obs)
    env.close()


@pytest.mark.parametrize("scale", [1.0, 1e3, 1e30])
def test_parameters_stay_in_their_ranges_for_any_finite_action(scale):
    rng = np.random.default_rng(0)
    actions = rng.standard_normal((1000, 5)) * scale
    params = action_to_parameters(actions)
    assert np.all(params >= PARAMETER_RANGES[:, 0]) and np.all(params <= PARAMETER_RANGES[:, 1])
    assert np.all(params[:, :4] > 0)  # frequencies and amplitudes positive


def test_action_parameter_round_trip_and_out_of_range():
    params = np.array(REFERENCE_PARAMETERS)
    np.testing.assert_allclose(action_to_parameters(parameters_to_action(params)), params)
    with pytest.raises(ValueError, match="outside the ranges"):
        parameters_to_action([10.0, 1.0, 0.1, 0.1, 0.0])


@pytest.mark.parametrize(
    "bad, message",
    [
        (np.full((2, 5), np.nan), "NaN or inf"),
        (np.full((2, 5), np.inf), "NaN or inf"),
        (np.zeros((2, 4)), "shape"),
        (np.zeros(5), "shape"),
        ("fast", "numbers"),
    ],
)
def test_bad_actions_raise_before_anything_is_stepped(bad, message):
    env = CPGParameterVectorEnv(2, config=SHORT)
    env.reset(seed=0)
    before = env.state.as_tensor().clone()
    with pytest.raises(ValueError, match=message):
        env.step(bad)
    assert torch.equal(env.state.as_tensor(), before)
    env.close()


def test_cpg_state_resets_with_the_episode():
    env = CPGParameterVectorEnv(2, config=HopperConfig(episode_steps=5))
    env.reset(seed=0)
    actions = parameters_to_action(np.array([REFERENCE_PARAMETERS] * 2))
    for _ in range(4):
        _, _, _, truncated, info = env.step(actions)
        assert not truncated.any()
    moved = env.state.as_tensor().clone()
    obs, _, _, truncated, info = env.step(actions)
    assert truncated.all()
    initial = env.cpg.initial_state(2).as_tensor()
    assert torch.equal(env.state.as_tensor(), initial)
    # the final observation still holds the CPG state of the finished episode
    assert not np.allclose(info["final_obs"][:, 12:14], obs[:, 12:14])
    assert not torch.equal(moved, initial)
    env.close()


def test_reference_parameters_make_the_leg_hop():
    (candidate,) = evaluate_parameters(np.array([REFERENCE_PARAMETERS]))
    assert candidate.hop_height > 0.2, candidate
    assert math.isfinite(candidate.episode_return)
