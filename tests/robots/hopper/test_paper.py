"""The hopper's parts of the paper's reproduction reach generic code through its registry
entry only (``Robot.paper``, ``Robot.commands``)."""

from __future__ import annotations

import numpy as np
import pytest

from cpg_actor.robots.registry import ROBOTS, get_robot, paper_robot


def test_the_paper_studies_the_hopper_and_its_entry_gives_the_report_its_parts():
    hopper = paper_robot()
    assert hopper is get_robot("hopper")
    parts = hopper.paper_parts()
    assert parts.reward_terms == ("r1", "r2", "r3", "r4", "r5")
    low, high = parts.joint_limits(None)  # traces saved without joint names: the hopper's
    np.testing.assert_allclose(low, [-0.5, -1.7])
    np.testing.assert_allclose(high, [1.3, 0.1])
    assert parts.joint_limits(("HFE", "KFE", "HAA")) is None  # another robot's traces


def test_a_robot_the_paper_does_not_study_says_so():
    with pytest.raises(ValueError, match="does not study the anymal"):
        get_robot("anymal").paper_parts()


def test_the_hopper_brings_its_commands_to_the_command_line():
    from cpg_actor.cli import COMMANDS, commands

    assert {"cpg-demo", "cho2019-reference"} <= set(ROBOTS["hopper"].commands)
    assert not {"cpg-demo", "cho2019-reference"} & set(COMMANDS)  # not listed by hand
    assert commands()["cpg-demo"][0] == "cpg_actor.robots.hopper.commands.cpg_demo"


def test_the_agents_list_the_cho2019_baselines_the_hopper_brings():
    from cpg_actor.agents import AGENTS, get_agent_spec
    from cpg_actor.robots.hopper import agents

    for spec in (agents.CHO2019, agents.CHO2019_WARM, agents.CHO2019_PAPER):
        assert get_agent_spec(spec.name) is spec and spec.name in sorted(AGENTS)


EXTRA = None  # a robot registered later brings this agent (below)


def test_a_robot_registered_later_brings_its_agents(monkeypatch):
    import dataclasses
    import sys

    from cpg_actor.agents import AGENTS, get_agent_spec
    from cpg_actor.robots.hopper.agents import CHO2019

    monkeypatch.setattr(sys.modules[__name__], "EXTRA", dataclasses.replace(CHO2019, name="x"))
    copy = dataclasses.replace(
        get_robot("hopper"), name="hopper-copy", agents=(f"{__name__}:EXTRA",), commands={}
    )
    monkeypatch.setitem(ROBOTS, copy.name, copy)
    try:
        assert get_agent_spec("x").name == "x"
    finally:
        del AGENTS["x"]
