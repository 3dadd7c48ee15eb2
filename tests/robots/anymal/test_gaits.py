"""The quadruped's CPG presets: each gait's phase relations are where the network settles, from
phases pushed away from them; the joint map drives HFE and KFE and holds HAA."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from cpg_actor.cpg import CPGState
from cpg_actor.robots.anymal.gaits import ANYMAL_GAITS
from cpg_actor.robots.common.quadruped.gaits import GAITS, OSCILLATOR_JOINTS, joint_map_for


def _wrap(angle):
    return (angle + math.pi) % (2 * math.pi) - math.pi


@pytest.mark.parametrize("gait", sorted(GAITS))
def test_each_gait_is_the_phase_locked_state_reached_from_elsewhere(gait):
    cpg = ANYMAL_GAITS.joint_cpg(0.01, gait).double()
    psi = np.array(ANYMAL_GAITS.gait_phases(gait))
    start = cpg.initial_state(1, amplitude=0.1)
    pushed = torch.as_tensor(psi + np.random.default_rng(0).uniform(-1.0, 1.0, 8))[None]
    state = CPGState(pushed, *start[1:])
    drive = torch.full((1, 8), 0.5, dtype=torch.float64)  # a 0.5 m/s command
    with torch.no_grad():
        for _ in range(1500):  # 15 s
            _, state = cpg(state, drive)
    theta = state.phase[0].numpy()
    for i in range(8):
        for j in range(8):
            assert abs(_wrap((theta[j] - theta[i]) - (psi[j] - psi[i]))) < 0.02, (gait, i, j)


def test_leg_phases_and_knee_lead_match_the_table():
    psi = ANYMAL_GAITS.gait_phases("walk")
    hips = [psi[2 * leg] for leg in range(4)]
    assert [h / (2 * math.pi) for h in hips] == pytest.approx(GAITS["walk"])
    assert psi[1] - psi[0] == pytest.approx(math.pi / 2)  # LF knee leads (front)
    assert psi[5] - psi[4] == pytest.approx(-math.pi / 2)  # LH knee lags (hind)
    topology = ANYMAL_GAITS.topology()
    assert len(topology.edges) == 12 + 8  # hips all to all, each knee with its hip
    with pytest.raises(ValueError, match="unknown gait"):
        ANYMAL_GAITS.gait_phases("gallop")


def test_the_joint_map_drives_hfe_and_kfe_and_holds_haa():
    nominal = torch.arange(12, dtype=torch.float64) / 10
    joint_map = joint_map_for(nominal.tolist()).double()
    x = torch.arange(1, 9, dtype=torch.float64)[None]
    out = joint_map(x)[0]
    assert out[list(OSCILLATOR_JOINTS)].tolist() == pytest.approx((nominal[list(
        OSCILLATOR_JOINTS)] + x[0]).tolist())  # fmt: skip
    assert out[[0, 3, 6, 9]].tolist() == pytest.approx(nominal[[0, 3, 6, 9]].tolist())
    with pytest.raises(ValueError, match="expects 8"):
        joint_map(torch.zeros(1, 12, dtype=torch.float64))
