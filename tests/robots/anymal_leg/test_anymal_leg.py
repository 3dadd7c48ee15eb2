"""The leg shared by the hopper and ANYmal B: both are built from its facts, the hopper's
rounded links round them, and its planar kinematics is the simulated leg's."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cpg_actor.robots.anymal import description as anymal
from cpg_actor.robots.anymal_leg import description as leg
from cpg_actor.robots.anymal_leg import kinematics
from cpg_actor.robots.hopper import description as hopper


def test_the_hoppers_links_are_the_right_front_leg_rounded():
    for link, ours in zip(("hip", "thigh", "shank", "adapter"), leg.LINKS, strict=True):
        rf = ours.mirrored(*hopper.RF)
        theirs = hopper.LINKS[link]
        assert theirs.mass == pytest.approx(rf.mass, abs=1e-5)
        assert theirs.com == pytest.approx(rf.com, abs=1e-4)
        assert theirs.inertia == pytest.approx(rf.inertia[:3], rel=2e-3)
    assert hopper.TOTAL_MASS == pytest.approx(leg.LEG_MASS, abs=1e-4)
    origins = [joint.origin for joint in hopper.JOINTS[1:]]
    assert origins == [(0.0635, -0.041, 0.0), (0.0, -0.109, -0.25), (0.1, 0.02, 0.0)]


def test_anymal_bs_legs_are_the_leg_mirrored():
    for name, (sx, sy) in anymal.LEG_SIGNS.items():
        bodies = anymal.LEG_BODIES[name]
        for (body, _, _), link in zip(bodies, leg.LINKS, strict=True):
            assert body.name == f"{name}_{link.name}" and body.mass == link.mass
            assert body.com == (link.com[0] * sx, link.com[1] * sy, link.com[2])
        # no negative zeros: the generated files write "0", never "-0"
        assert all(math.copysign(1, v) > 0 for _, origin, _ in bodies for v in origin if v == 0)
    assert anymal.LEG_BODIES["LF"][1][1] == leg.HFE_ORIGIN


def test_the_foot_in_the_nominal_pose():
    """The foot centre 0.11 m in front of and 0.47 m below the HFE axis, knee bent backwards."""
    foot = kinematics.foot_position(np.array([leg.NOMINAL_HFE, leg.NOMINAL_KFE]))
    knee = kinematics.knee_position(np.array([leg.NOMINAL_HFE, leg.NOMINAL_KFE]))
    x, z = foot - np.array(kinematics.HFE_ORIGIN)
    assert x == pytest.approx(0.11, abs=0.01) and z == pytest.approx(-0.47, abs=0.01)
    assert knee[0] < kinematics.HFE_ORIGIN[0]  # the knee points backwards
