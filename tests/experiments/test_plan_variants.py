"""Every named variant of `cpg-actor reproduce` composes into a valid run config."""

import pytest

from cpg_actor.config import compose_config
from cpg_actor.experiments.plan import VARIANTS, variant_agent


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_each_variant_is_its_agent_with_its_settings(variant):
    agent, overrides = variant_agent(variant)
    # follow scales the CPG's own rate, which the throughput preset sets and the paper's not
    preset = "throughput" if variant == "cpg-actor-follow" else "paper"
    config = compose_config(preset, values={"agent": agent}, overrides=overrides)
    assert config.agent == agent
    if variant.endswith("-randomized"):
        assert config.env.randomize.active
    if variant == "cpg-actor-follow":
        assert config.ppo.cpg_lr_schedule == "follow"
    if variant.endswith("-floor"):
        assert config.agent_config.action_std_floor == (0 if "no-floor" in variant else 0.1)
