"""The quadruped's ``leg`` layout on ANYmal B: one oscillator per leg, a foot-space pattern
through the leg's inverse kinematics (cpg_actor.robots.common.quadruped.foot_space), and its CPG
(each gait's phase lags are where the network settles)."""

import math

import numpy as np
import pytest
import torch

from cpg_actor.cpg import CPGState
from cpg_actor.robots.anymal import description as robot
from cpg_actor.robots.anymal.gaits import ANYMAL_GAITS
from cpg_actor.robots.anymal_leg import kinematics
from cpg_actor.robots.common.quadruped.foot_space import leg_foot
from cpg_actor.robots.common.quadruped.gaits import GAITS

NOMINAL = torch.tensor(robot.NOMINAL_POSE, dtype=torch.float64)


@pytest.fixture(scope="module")
def pattern():
    return ANYMAL_GAITS.foot_space(robot.NOMINAL_POSE).double()


def feet(joints: torch.Tensor) -> torch.Tensor:
    """(B, 4, 2) foot centres (x forward, z) relative to each leg's HFE axis, by the leg's
    forward kinematics (an independent reference), the hind legs mirrored front to back."""
    q = joints.reshape(-1, 4, 3)[..., 1:].numpy()
    signs = np.array([1, 1, -1, -1])[None, :, None]
    xz = kinematics.foot_position(q * signs) - np.array(kinematics.HFE_ORIGIN)
    return torch.as_tensor(xz * np.array([1, 1, -1, -1])[None, :, None] ** [1, 0])


def test_zero_amplitude_at_phase_zero_is_the_nominal_pose(pattern):
    zeros = torch.zeros(3, 4, dtype=torch.float64)
    assert torch.allclose(pattern(zeros, zeros), NOMINAL.expand(3, 12), atol=1e-12)


def test_the_feet_follow_the_pattern(pattern):
    """Swing (0 < theta < pi): the foot forward by -r cos(theta) and up by clearance sin(theta);
    stance: pressed down by penetration |sin(theta)|; every foot (hind legs mirrored) where
    the pattern puts it, by forward kinematics; HAA at the nominal pose."""
    theta = torch.linspace(0, 2 * math.pi, 25, dtype=torch.float64)[:, None].expand(25, 4)
    r = torch.tensor([0.02, 0.04, 0.06, 0.08], dtype=torch.float64).expand(25, 4)
    joints = pattern(theta, r)
    nominal_feet = feet(NOMINAL[None])[0]
    got = feet(joints) - nominal_feet
    s = torch.sin(theta)
    dz = torch.where(s > 0, ANYMAL_GAITS.clearance * s, ANYMAL_GAITS.penetration * s)
    assert torch.allclose(got[..., 0], -r * torch.cos(theta), atol=1e-9)
    assert torch.allclose(got[..., 1], dz, atol=1e-9)
    assert torch.equal(joints.reshape(25, 4, 3)[..., 0], torch.zeros(25, 4, dtype=torch.float64))
    low = torch.tensor([robot.JOINT_LIMITS[j][0] for j in robot.JOINT_NAMES], dtype=torch.float64)
    high = torch.tensor([robot.JOINT_LIMITS[j][1] for j in robot.JOINT_NAMES], dtype=torch.float64)
    assert bool(((joints >= low) & (joints <= high)).all())  # within the joint ranges


def test_inverse_kinematics_inverts_forward_kinematics(pattern):
    hfe = torch.empty(200, dtype=torch.float64).uniform_(-0.3, 1.1)
    kfe = torch.empty(200, dtype=torch.float64).uniform_(-1.6, -0.3)  # the front knee's side
    x, z = leg_foot(hfe, kfe, ANYMAL_GAITS.thigh, ANYMAL_GAITS.shank)
    h, k = pattern.inverse_kinematics(x, z)
    assert torch.allclose(h, hfe, atol=1e-9) and torch.allclose(k, kfe, atol=1e-9)


def test_gradients_reach_phase_and_amplitude(pattern):
    theta = torch.full((2, 4), 1.0, dtype=torch.float64, requires_grad=True)
    r = torch.full((2, 4), 0.05, dtype=torch.float64, requires_grad=True)
    pattern(theta, r).sum().backward()
    assert torch.isfinite(theta.grad).all() and (theta.grad != 0).all()
    assert torch.isfinite(r.grad).all() and (r.grad != 0).all()


def test_legs_must_mirror_the_front_leg():
    pose = list(robot.NOMINAL_POSE)
    pose[4] = 0.5  # RF HFE unlike LF's
    with pytest.raises(ValueError, match="front leg or its mirror image"):
        ANYMAL_GAITS.foot_space(pose)


@pytest.mark.parametrize("gait", sorted(GAITS))
def test_each_gait_is_the_phase_locked_state_of_the_leg_cpg(gait):
    cpg = ANYMAL_GAITS.leg_cpg(0.01, gait).double()
    psi = 2 * math.pi * np.array(GAITS[gait])
    start = cpg.initial_state(1, amplitude=0.05)
    pushed = torch.as_tensor(psi + np.random.default_rng(1).uniform(-1.0, 1.0, 4))[None]
    state = CPGState(pushed, *start[1:])
    drive = torch.full((1, 4), 0.5, dtype=torch.float64)
    with torch.no_grad():
        for _ in range(1500):
            _, state = cpg(state, drive)
    theta = state.phase[0].numpy()
    for i in range(4):
        for j in range(4):
            lag = (theta[j] - theta[i]) - (psi[j] - psi[i])
            assert abs((lag + math.pi) % (2 * math.pi) - math.pi) < 0.02, (gait, i, j)
    rho = cpg.oscillator_parameters(drive).amplitude[0]
    assert torch.allclose(state.amplitude[0], rho, rtol=1e-3)  # 0.01 + 0.08 x 0.5 m
    assert torch.allclose(rho, torch.full((4,), 0.05, dtype=torch.float64))
