"""Every named variant of `cpg-actor reproduce` composes into a valid run config."""

import pytest

from cpg_actor.config import compose_config
from cpg_actor_studies.reproduction.plan import (
    VARIANT_RECIPES,
    VARIANTS,
    variant_agent,
    variant_preset,
)

# the robot each variant with a recipe of its own runs on (the one whose config defines it)
RECIPE_ROBOTS = {"mlp-playground": "go1", "mlp-legged-gym": "anymal"}


def test_each_recipe_variant_names_its_robot():
    assert set(RECIPE_ROBOTS) == set(VARIANT_RECIPES)


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_each_variant_is_its_agent_with_its_settings(variant):
    agent, overrides = variant_agent(variant)
    # follow scales the CPG's own rate, which the throughput preset sets and the paper's not
    preset = "throughput" if variant == "cpg-actor-follow" else "paper"
    values = {"agent": agent}
    if variant.endswith("-field"):  # the field's recipe is the quadrupeds'
        preset, values["robot"] = "omni", "go1"
    if variant in VARIANT_RECIPES:  # a recipe of its own, on the robot that defines it
        preset, values["robot"] = variant_preset(variant, "paper"), RECIPE_ROBOTS[variant]
    config = compose_config(preset, values=values, overrides=overrides)
    assert config.agent == agent
    assert config.preset == variant_preset(variant, preset)
    if variant.endswith("-randomized"):
        assert config.env.randomize.active
    if variant == "cpg-actor-follow":
        assert config.ppo.cpg_lr_schedule == "follow"
    if variant.endswith("-floor"):
        assert config.agent_config.action_std_floor == (0 if "no-floor" in variant else 0.1)


def test_the_field_mlp_recipe_on_the_go1s_omnidirectional_task():
    """mlp-field: rsl_rl's actor-critic and PPO weights over the Go1's omni task, whose command
    ranges and recipe (throughput) stay the task's."""
    from cpg_actor_studies.reproduction import plan

    settings = plan.ReproduceSettings(["mlp-field"], 1, 2_000_000, overrides=["robot=go1"],
                                      preset="omni")  # fmt: skip
    config = plan.resolve_config(settings, "mlp-field")
    assert (config.agent, config.robot, config.preset) == ("mlp", "go1", "omni")
    assert config.agent_config.actor_hidden == config.agent_config.critic_hidden == (512, 256, 128)
    assert config.agent_config.activation == "elu"
    assert (config.ppo.entropy_coef, config.ppo.value_loss_coef, config.ppo.max_grad_norm) == (
        0.01, 1.0, 1.0)  # fmt: skip
    assert (config.ppo.learning_rate, config.ppo.lr_schedule) == (1e-3, "adaptive")
    assert config.env.yaw_range == (-1.0, 1.0) and config.num_envs == 256
    assert config.env.tracking_sigma == 0.25  # its tuning's choice (the task's own is 0.1)
    own = plan.resolve_config(plan.ReproduceSettings(["cpg-actor"], 1, 2_000_000,
                              overrides=["robot=go1"], preset="omni"), "cpg-actor")  # fmt: skip
    assert own.env.tracking_sigma == 0.1
    warm = plan.resolve_config(
        plan.ReproduceSettings(["mlp-warm-field"], 1, 2_000_000, overrides=["robot=go1"],
                               preset="omni"), "mlp-warm-field")  # fmt: skip
    assert (warm.agent, warm.agent_config.cpg_layout, warm.agent_config.init_std) == (
        "mlp-warm", "leg", 0.3)  # fmt: skip
    assert warm.agent_config.actor_hidden == (512, 256, 128)
    assert warm.env.tracking_sigma == 0.25
