"""A change of gait at run time (``GaitTransition``): a robot trotting open loop (the leg
layout, planar steps, a forward command) moves into another gait over 2 s without a fall, its
legs' lags end at the new gait's, and no joint command jumps."""

import math

import numpy as np
import pytest
import torch

from cpg_actor.robots.common.quadruped.gait_transition import GaitTransition
from cpg_actor.robots.plugin import load
from cpg_actor.robots.registry import get_robot

ROBOTS = 2
BEFORE, RAMP, AFTER = 50, 100, 200  # control steps (50 Hz): trot 1 s, 2 s ramp, 4 s after


@pytest.mark.parametrize(("name", "gait"), [("go1", "pace"), ("anymal", "bound")])
def test_a_trot_turns_into_another_gait_without_a_fall(name, gait):
    robot = get_robot(name)
    gaits = load(robot.cpg_layouts.args[0])  # the robot's GaitCPGs
    config = robot.config_class().replace(command_range=(0.3, 0.3), episode_seconds=20.0)
    env = robot.make(ROBOTS, config, num_threads=1)
    layout = robot.cpg_layouts()["leg"]
    cpg = layout.preset(env.robot.control_dt, gait="trot").double()
    pattern = layout.pattern(env.robot.nominal_pose).double()
    command = torch.tensor([[0.3, 0.0, 0.0]] * ROBOTS, dtype=torch.float64)
    drive, direction = layout.planar_drive().double()(command)
    state = cpg.initial_state(ROBOTS)
    env.reset(seed=0)
    transition = GaitTransition(gaits, cpg, gait, steps=RAMP)
    joints, fell = [], np.zeros(ROBOTS, dtype=bool)
    with torch.no_grad():
        for k in range(BEFORE + RAMP + AFTER):
            if k >= BEFORE:
                transition.step()
            _, state = cpg(state, drive)
            joints.append(pattern(state.phase, state.amplitude, direction).numpy())
            _, _, terminated, truncated, _ = env.step(joints[-1])
            fell |= terminated | truncated
    env.close()
    assert transition.done and not fell.any()
    lags = ((state.phase - state.phase[:, :1]) / (2 * math.pi)).numpy()
    target = np.array(gaits.footfalls()[gait]) - gaits.footfalls()[gait][0]
    error = (lags - target + 0.5) % 1.0 - 0.5  # fractions of a cycle
    assert np.abs(error).max() < 0.03
    change = np.abs(np.diff(np.array(joints), axis=0)).max(axis=(1, 2))  # per step, rad
    assert change[BEFORE:].max() < 1.5 * change[BEFORE // 2 : BEFORE].max()


def test_a_transition_needs_a_gait_cpg_and_steps():
    gaits = load(get_robot("go1").cpg_layouts.args[0])
    cpg = gaits.leg_cpg(0.02)
    with pytest.raises(ValueError, match="steps must be an integer >= 1"):
        GaitTransition(gaits, cpg, "walk", 0)
    with pytest.raises(ValueError, match="unknown gait 'gallop'"):
        GaitTransition(gaits, cpg, "gallop", 10)
    frozen = gaits.leg_cpg(0.02, frozen={"phase_bias": True})
    with pytest.raises(ValueError, match="phase biases trainable"):
        GaitTransition(gaits, frozen, "walk", 10)
