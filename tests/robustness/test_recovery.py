"""Recovery from a push, from gait cycles: the hopper's hops, a quadruped's strides."""

import math

import numpy as np

from cpg_actor.robots.common.quadruped.perturbations import strides
from cpg_actor.robots.hopper.perturbations import hops
from cpg_actor.robustness.recovery import nominal_cycle, recovery_steps


def test_a_gait_is_back_when_every_cycle_to_the_end_is_within_10_percent():
    bounds = np.arange(0, 110, 10)  # ten cycles of 10 steps
    values = np.array([0.5, 0.5, 0.5, 0.2, 0.3, 0.42, 0.47, 0.52, 0.5, 0.49])
    reference = nominal_cycle(bounds, np.full(10, 0.5), after=0)
    assert reference == 0.5
    # pushed at step 33: cycles 3-5 are off, the steady run starts at cycle 6 (step 60)
    assert recovery_steps(bounds, values, 33, reference) == 60 - 33
    # a push that changes nothing: the cycle it came in is already back
    assert recovery_steps(bounds, np.full(10, 0.5), 33, reference) == 0
    # never back, or back for one cycle only at the end: not recovered
    assert recovery_steps(bounds, np.full(10, 0.3), 33, reference) is None
    assert recovery_steps(bounds, [*[0.3] * 9, 0.5], 33, reference) is None
    # the floor: an absolute tolerance where 10 % of the cycle is less
    assert recovery_steps(bounds, np.full(10, 0.02), 33, 0.0, floor=0.05) == 0
    # no nominal gait (fewer than two cycles after the push): undefined
    assert math.isnan(nominal_cycle(bounds, np.full(10, 0.5), after=95))
    assert math.isnan(recovery_steps(bounds, values, 33, math.nan))


def test_hops_and_strides_are_the_cycles_between_touchdowns():
    steps = 40
    foot = np.where(np.arange(steps) % 10 < 4, 0.0, 0.05)  # touching for 4 steps of every 10
    hip = 0.5 + np.where(np.arange(steps) % 10 < 4, 0.0, 0.1 * (np.arange(steps) // 10 + 1))
    traces = {"hip_height": hip[:, None], "foot_height": foot[:, None],
              "standing_hip_height": np.array(0.5)}  # fmt: skip
    bounds, apex = hops(traces, 0)
    np.testing.assert_array_equal(bounds, [10, 20, 30])
    np.testing.assert_allclose(apex, [0.2, 0.3])
    contact = np.zeros((steps, 1, 4))
    contact[:, 0, 0] = foot == 0.0
    speed = np.repeat([0.1, 0.2, 0.3, 0.4], 10)[:, None]
    bounds, mean = strides({"foot_contact": contact, "base_forward_speed": speed}, 0)
    np.testing.assert_array_equal(bounds, [10, 20, 30])
    np.testing.assert_allclose(mean, [0.2, 0.3])
