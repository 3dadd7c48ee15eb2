"""legged_gym's ANYmal B recipe (``--preset legged_gym``, the ``mlp-legged-gym`` variant): each
of its numbers beside its source, the observation's fixed scales, the heading command, the
start, the clipped reward, the uniform noise, a saved state and a tiny training."""

import argparse
import json
import math

import numpy as np
import pytest
import torch

from cpg_actor.agents.base import AgentConfig, observation_scale
from cpg_actor.agents.mlp import MLPAgent
from cpg_actor.config import compose_config
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.common.quadruped.vector import draw_command
from cpg_actor.robots.registry import get_robot
from cpg_actor.tasks import velocity as task
from cpg_actor_studies.reproduction import plan

LEGGED_GYM = "legged_gym 8fa29ac "
BASE = LEGGED_GYM + "envs/base/legged_robot_config.py LeggedRobotCfg"
ROUGH = LEGGED_GYM + "envs/anymal_c/mixed_terrains/anymal_c_rough_config.py AnymalCRoughCfg"
FLAT = LEGGED_GYM + "envs/anymal_c/flat/anymal_c_flat_config.py AnymalCFlatCfg"
ROBOT = LEGGED_GYM + "envs/base/legged_robot.py LeggedRobot"
PPO_CFG = LEGGED_GYM + "envs/base/legged_robot_config.py LeggedRobotCfgPPO"
RSL_RL = "rsl_rl v1.0.2 "

# (the resolved config's value, the recipe's number, its source)
RECIPE = [
    ("env.kp", 80.0, ROUGH + " control.stiffness"),
    ("env.kd", 2.0, ROUGH + " control.damping"),
    ("env.action_scale", 0.5, ROUGH + " control.action_scale"),
    ("env.physics_dt", 0.005, BASE + " sim.dt"),
    ("env.decimation", 4, ROUGH + " control.decimation"),
    ("env.control_dt", 0.02, ROBOT + " _parse_cfg: dt = decimation x sim.dt"),
    ("env.episode_steps", 1000, BASE + " env.episode_length_s 20"),
    ("env.reward_scales.tracking_lin_vel", 1.0, BASE + " rewards.scales"),
    ("env.reward_scales.tracking_ang_vel", 0.5, BASE + " rewards.scales"),
    ("env.reward_scales.lin_vel_z", -2.0, BASE + " rewards.scales"),
    ("env.reward_scales.ang_vel_xy", -0.05, BASE + " rewards.scales"),
    ("env.reward_scales.orientation", 0.0, BASE + " rewards.scales (-0.)"),
    ("env.reward_scales.base_height", 0.0, BASE + " rewards.scales (-0.)"),
    ("env.reward_scales.torques", -1e-5, BASE + " rewards.scales"),
    ("env.reward_scales.joint_acc", -2.5e-7, BASE + " rewards.scales.dof_acc"),
    ("env.reward_scales.action_rate", -0.01, BASE + " rewards.scales"),
    ("env.reward_scales.feet_air_time", 1.0, BASE + " rewards.scales"),
    ("env.reward_scales.feet_slip", 0.0, "not a legged_gym term"),
    ("env.reward_clip_min", 0.0, BASE + " rewards.only_positive_rewards"),
    ("env.tracking_sigma", 0.25, BASE + " rewards.tracking_sigma"),
    ("env.base_height_target", 0.5, ROUGH + " rewards.base_height_target"),
    ("env.soft_joint_limit_factor", 1.0, BASE + " rewards.soft_dof_pos_limit"),
    ("env.observe_lin_vel", True, ROBOT + " compute_observations: base_lin_vel first"),
    ("env.privileged_observation", False, BASE + " env.num_privileged_obs None"),
    ("env.observation_noise.lin_vel", 0.1, BASE + " noise.noise_scales (noise_level 1)"),
    ("env.observation_noise.gyro", 0.2, BASE + " noise.noise_scales.ang_vel"),
    ("env.observation_noise.gravity", 0.05, BASE + " noise.noise_scales"),
    ("env.observation_noise.joint_pos", 0.01, BASE + " noise.noise_scales.dof_pos"),
    ("env.observation_noise.joint_vel", 1.5, BASE + " noise.noise_scales.dof_vel"),
    ("env.command_range", (-1.0, 1.0), BASE + " commands.ranges.lin_vel_x"),
    ("env.lateral_range", (-1.0, 1.0), BASE + " commands.ranges.lin_vel_y"),
    ("env.yaw_range", (-1.0, 1.0), ROBOT + " _post_physics_step_callback: clip(..., -1, 1)"),
    ("env.heading_gain", 0.5, ROBOT + " _post_physics_step_callback: 0.5 wrap_to_pi(...)"),
    ("env.heading_range", (-3.14, 3.14), BASE + " commands.ranges.heading"),
    ("env.min_command_speed", 0.2, ROBOT + " _resample_commands: norm(command_xy) > 0.2"),
    ("env.command_resample_seconds", 10.0, BASE + " commands.resampling_time"),
    ("env.command_interval", "fixed", ROBOT + " episode_length_buf % resampling steps"),
    ("env.standing_share", 0.0, ROBOT + " _resample_commands (only the small ones zeroed)"),
    ("env.command_nonzero", None, ROBOT + " _resample_commands"),
    ("env.reset_noise", 0.0, ROBOT + " _reset_dofs"),
    ("env.reset_joint_scale", (0.5, 1.5), ROBOT + " _reset_dofs: default x U(0.5, 1.5)"),
    ("env.reset_base_velocity", 0.5, ROBOT + " _reset_root_states: U(-0.5, 0.5) x 6"),
    ("env.fall_tilt", math.pi, ROBOT + " check_termination: base contact alone"),
    ("env.randomize.friction", ((0.5 + 1.0) / 2, (1.25 + 1.0) / 2),
     BASE + " domain_rand.friction_range, averaged with the plane's 1.0 (" + FLAT + ")"),
    ("env.randomize.payload", (0.0, 5.0), ROUGH + " domain_rand.added_mass_range, its >= 0 half"),
    ("env.randomize.push_velocity", (0.0, 1.0), BASE + " domain_rand.max_push_vel_xy"),
    ("env.randomize.push_interval", (15.0, 15.0), BASE + " domain_rand.push_interval_s"),
    ("agent", "mlp", PPO_CFG + " runner.policy_class_name ActorCritic"),
    ("agent_config.actor_hidden", (512, 256, 128), PPO_CFG + " policy.actor_hidden_dims"),
    ("agent_config.critic_hidden", (512, 256, 128), PPO_CFG + " policy.critic_hidden_dims"),
    ("agent_config.activation", "elu", PPO_CFG + " policy.activation"),
    ("agent_config.init_std", 1.0, PPO_CFG + " policy.init_noise_std"),
    ("agent_config.action_std_floor", 0.0, RSL_RL + "modules/actor_critic.py (none)"),
    ("ppo.num_steps", 24, PPO_CFG + " runner.num_steps_per_env"),
    ("ppo.num_epochs", 5, PPO_CFG + " algorithm.num_learning_epochs"),
    ("ppo.num_minibatches", 4, PPO_CFG + " algorithm.num_mini_batches"),
    ("ppo.learning_rate", 1e-3, PPO_CFG + " algorithm.learning_rate"),
    ("ppo.lr_schedule", "adaptive", PPO_CFG + " algorithm.schedule"),
    ("ppo.desired_kl", 0.01, PPO_CFG + " algorithm.desired_kl"),
    ("ppo.min_learning_rate", 1e-5, RSL_RL + "algorithms/ppo.py update: max(1e-5, lr / 1.5)"),
    ("ppo.max_learning_rate", 1e-2, RSL_RL + "algorithms/ppo.py update: min(1e-2, lr * 1.5)"),
    ("ppo.entropy_coef", 0.01, PPO_CFG + " algorithm.entropy_coef"),
    ("ppo.gamma", 0.99, PPO_CFG + " algorithm.gamma"),
    ("ppo.gae_lambda", 0.95, PPO_CFG + " algorithm.lam"),
    ("ppo.clip_ratio", 0.2, PPO_CFG + " algorithm.clip_param"),
    ("ppo.clip_value_loss", True, PPO_CFG + " algorithm.use_clipped_value_loss"),
    ("ppo.value_loss_coef", 1.0, PPO_CFG + " algorithm.value_loss_coef"),
    ("ppo.max_grad_norm", 1.0, PPO_CFG + " algorithm.max_grad_norm"),
    ("ppo.normalize_observations", False, RSL_RL + "runners/on_policy_runner.py (none)"),
    ("ppo.normalize_rewards", False, RSL_RL + "(scales no reward)"),
    ("ppo.adam_eps", 1e-8, RSL_RL + "algorithms/ppo.py optim.Adam (torch's default eps)"),
]  # fmt: skip

OBS_SCALES = BASE + " normalization.obs_scales"
# (an observation entry, its fixed scale, its source)
SCALES = [
    ("base_lin_vel_x", 2.0, OBS_SCALES + ".lin_vel"),
    ("base_ang_vel_z", 0.25, OBS_SCALES + ".ang_vel"),
    ("projected_gravity_z", 1.0, ROBOT + " compute_observations: gravity unscaled"),
    ("command_vx", 2.0, ROBOT + " commands_scale (lin_vel)"),
    ("command_vy", 2.0, ROBOT + " commands_scale (lin_vel)"),
    ("command_yaw", 0.25, ROBOT + " commands_scale (ang_vel)"),
    ("LF_HAA_pos", 1.0, OBS_SCALES + ".dof_pos"),
    ("RH_KFE_vel", 0.05, OBS_SCALES + ".dof_vel"),
    ("LH_HFE_last_action", 2.0, ROBOT + " compute_observations: the action a = 2 x 0.5 a"),
]


@pytest.fixture(scope="module")
def recipe():
    settings = plan.ReproduceSettings(["mlp-legged-gym"], 1, 100_000,
                                      overrides=["robot=anymal"], first_seed=100)  # fmt: skip
    return plan.resolve_config(settings, "mlp-legged-gym")


def resolved(config, path: str):
    value = config
    for part in path.split("."):
        value = value[part] if isinstance(value, dict) else getattr(value, part)
    return value


@pytest.mark.parametrize("path, number, source", RECIPE, ids=[row[0] for row in RECIPE])
def test_each_recipe_number_is_its_sources(recipe, path, number, source):
    value = resolved(recipe, path)
    if isinstance(number, float):
        assert value == pytest.approx(number, rel=1e-9), source
    elif isinstance(number, tuple) and isinstance(number[0], float):
        assert value == pytest.approx(number, rel=1e-9), source
    else:
        assert value == number, source


@pytest.mark.parametrize("name, scale, source", SCALES, ids=[row[0] for row in SCALES])
def test_each_observation_entry_is_scaled_as_legged_gym_scales_it(recipe, name, scale, source):
    names = get_robot("anymal").make(1, recipe.env, 1).robot.observation_names
    assert name in names
    factors = dict(zip(names, observation_scale(names, recipe.agent_config.observation_scales),
                       strict=True))  # fmt: skip
    assert factors[name] == scale, source


def test_the_variant_the_command_line_and_the_other_recipes(recipe):
    """mlp-legged-gym runs under its own recipe whatever the reproduction's preset; the
    command line resolves the same; no other recipe sets the recipe's new options."""
    from cpg_actor.commands.train import add_arguments, build_config

    assert (recipe.robot, recipe.preset, recipe.agent) == ("anymal", "legged_gym", "mlp")
    omni = plan.ReproduceSettings(["mlp-legged-gym", "mlp-field"], 1, 100_000,
                                  overrides=["robot=anymal"], preset="omni",
                                  first_seed=100)  # fmt: skip
    assert plan.resolve_config(omni, "mlp-legged-gym").to_dict() == recipe.to_dict()
    assert plan.resolve_config(omni, "mlp-field").preset == "omni"
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    argv = ["--robot", "anymal", "--agent", "mlp", "--preset", "legged_gym",
            "--total-steps", "100000"]  # fmt: skip
    assert build_config(parser.parse_args(argv)).to_dict() == recipe.to_dict()
    new = {"heading_gain": 0.0, "min_command_speed": 0.0, "reset_joint_scale": None,
           "reset_base_velocity": 0.0}  # fmt: skip
    for preset, robot in (("paper", "anymal"), ("throughput", "anymal"), ("omni", "anymal"),
                          ("anymal", "anymal"), ("throughput", "go1"), ("omni", "go1"),
                          ("playground", "go1")):  # fmt: skip
        config = compose_config(preset, values={"robot": robot, "agent": "mlp"})
        assert {k: getattr(config.env, k) for k in new} == new, (preset, robot)
        assert config.agent_config.observation_scales == {}


def test_a_robot_without_the_recipe_and_an_agent_without_scales_are_refused_in_one_line():
    for robot, config in (("go1", "Go1Config"), ("hopper", "HopperConfig")):
        with pytest.raises(ValueError, match=f"config {config} has no LEGGED_GYM") as error:
            compose_config("legged_gym", values={"robot": robot, "agent": "mlp"})
        assert "\n" not in str(error.value)
    with pytest.raises(ValueError, match="observation_scales: agent 'cpg-actor'") as error:
        compose_config("legged_gym", values={"robot": "anymal", "agent": "cpg-actor"})
    assert "\n" not in str(error.value)
    with pytest.raises(ValueError, match="MuJoCo's only"):
        QuadrupedConfig(sim="mjx", heading_gain=0.5).validate()
    with pytest.raises(ValueError, match="reset_joint_scale"):
        QuadrupedConfig(reset_joint_scale=(1.5, 0.5)).validate()
    with pytest.raises(ValueError, match="heading_gain"):
        QuadrupedConfig(heading_gain=-1.0).validate()
    with pytest.raises(ValueError, match="observation_scales"):
        AgentConfig(observation_scales={"x": 0.0}).validate()


def recipe_env(num_envs: int, **changes):
    """ANYmal B's env under the recipe (without its randomisation), ``changes`` made."""
    values = {k: v for k, v in QuadrupedConfig.LEGGED_GYM.items() if k != "randomize"}
    return get_robot("anymal").make(num_envs, QuadrupedConfig.from_dict({**values, **changes}), 1)


def test_the_heading_command_turns_the_base_toward_its_heading():
    yaw_of = task.base_yaw
    turned = np.array([[math.cos(0.5), 0.0, 0.0, math.sin(0.5)]])  # 1 rad about z
    assert yaw_of(turned)[0] == pytest.approx(1.0, rel=1e-12)
    level = np.array([[1.0, 0.0, 0.0, 0.0]] * 3)
    rate = task.heading_yaw_rate(level, np.array([0.5, 3.0, -1.0]), 0.5, -1.0, 1.0)
    assert rate == pytest.approx([0.25, 1.0, -0.5], rel=1e-12)  # 3 rad: clipped at 1
    back = np.array([[math.cos(1.5), 0.0, 0.0, math.sin(1.5)]])  # yaw 3 rad
    wrapped = task.heading_yaw_rate(back, np.array([-3.0]), 0.5, -1.0, 1.0)  # -6 is 2 pi - 6
    assert wrapped[0] == pytest.approx(0.5 * (2 * math.pi - 6.0), rel=1e-9)
    env = recipe_env(3, command_resample_seconds=0.1)  # a new heading every 5 steps
    try:
        env.reset(seed=100)
        column = env.robot.observation_names.index("command_yaw")
        home = np.tile(np.asarray(env.robot.nominal_pose), (3, 1))
        headings = [env._heading.copy()]
        for step in range(1, 13):
            obs, _, terminated, truncated, _ = env.step(home)
            assert not (terminated | truncated).any()
            expected = task.heading_yaw_rate(env.qpos[:, 3:7], env._heading, 0.5, -1.0, 1.0)
            assert env.command[:, 2] == pytest.approx(expected, rel=1e-12)
            assert obs[:, column] == pytest.approx(expected, rel=1e-6)  # no noise on it
            changed = not np.array_equal(headings[-1], env._heading)
            assert changed == (step % 5 == 0), step
            headings.append(env._heading.copy())
    finally:
        env.close()


def test_small_commands_are_zeroed_and_the_task_streams_stay_as_they_were():
    config = QuadrupedConfig(command_range=(-0.14, 0.14), lateral_range=(-0.14, 0.14),
                             yaw_range=(-1.0, 1.0), min_command_speed=0.2)  # fmt: skip
    rng = np.random.default_rng(0)
    draws = np.array([draw_command(rng, config) for _ in range(100)])
    assert (draws[:, :2] == 0).all() and (draws[:, 2] != 0).all()
    heading = QuadrupedConfig(lateral_range=(-1.0, 1.0), yaw_range=(-1.0, 1.0), heading_gain=0.5)
    assert all(draw_command(rng, heading)[2] == 0.0 for _ in range(10))  # not drawn
    forward, again = np.random.default_rng(1), np.random.default_rng(1)
    assert draw_command(forward, QuadrupedConfig())[0] == again.uniform(0.0, 1.0)


def test_the_start_scales_the_joints_and_moves_the_base():
    env = recipe_env(16)
    try:
        env.reset(seed=101)
        nominal = np.asarray(env.robot.nominal_pose)
        ratio = np.divide(env.qpos[:, 7:], nominal, out=np.ones((16, 12)), where=nominal != 0)
        assert ((ratio >= 0.5) & (ratio <= 1.5)).all() and ratio.std() > 0.1
        assert (env.qpos[:, 7:][:, nominal == 0] == 0).all()  # HAA: 0 x anything
        base = env.qvel[:, :6]
        assert (np.abs(base) <= 0.5).all() and np.abs(base).mean() == pytest.approx(0.25, rel=0.3)
    finally:
        env.close()
    default = get_robot("anymal").make(4, QuadrupedConfig(), 1)
    try:
        default.reset(seed=101)
        assert (default.qvel == 0).all()
        assert np.abs(default.qpos[:, 7:] - np.asarray(default.robot.nominal_pose)).max() <= 0.1
    finally:
        default.close()


def test_the_robot_stands_on_the_recipes_physics_and_the_clipped_reward_is_never_negative():
    env = recipe_env(4)
    try:
        env.reset(seed=102)
        home = np.tile(np.asarray(env.robot.nominal_pose), (4, 1))
        for _ in range(100):  # 2 s at the default pose
            _, reward, terminated, _, _ = env.step(home)
            assert not terminated.any() and (reward >= 0).all()
        rng = np.random.default_rng(0)
        low, high = env.single_action_space.low, env.single_action_space.high
        rewards, sums = [], []
        for _ in range(200):
            _, reward, _, _, info = env.step(rng.uniform(low, high, (4, 12)))
            rewards.append(reward)
            sums.append(sum(info["reward_terms"].values()))
        assert (np.concatenate(rewards) >= 0.0).all()
        assert (np.concatenate(sums) < 0.0).any()
        assert "termination" not in info["reward_terms"]  # its scale is 0
    finally:
        env.close()


def test_the_observation_noise_is_uniform_of_the_stated_half_widths():
    """The same env without the noise follows the same states for the first steps (no command
    is drawn yet): the observations differ by the noise alone."""
    noisy, clean = recipe_env(8), recipe_env(8, observation_noise={})
    try:
        noisy.reset(seed=103)
        clean.reset(seed=103)
        names = noisy.robot.observation_names
        groups = {
            "gyro": [f"base_ang_vel_{a}" for a in "xyz"],
            "gravity": [f"projected_gravity_{a}" for a in "xyz"],
            "lin_vel": [f"base_lin_vel_{a}" for a in "xyz"],
            "joint_pos": [f"{j}_pos" for j in noisy.robot.joint_names],
            "joint_vel": [f"{j}_vel" for j in noisy.robot.joint_names],
        }
        noise = {group: [] for group in groups}
        home = np.tile(np.asarray(noisy.robot.nominal_pose), (8, 1))
        for _ in range(40):
            obs, *_ = noisy.step(home)
            truth, *_ = clean.step(home)
            for group, entries in groups.items():
                columns = [names.index(n) for n in entries]
                noise[group].append(obs[:, columns] - truth[:, columns])
        for group, width in QuadrupedConfig.LEGGED_GYM["observation_noise"].items():
            drawn = np.concatenate(noise[group]).ravel()
            assert np.abs(drawn).max() <= width * (1 + 1e-4) + 1e-5, group
            assert drawn.std() == pytest.approx(width / math.sqrt(3), rel=0.15), group
    finally:
        noisy.close()
        clean.close()


def test_the_mlp_reads_the_scaled_observation_and_keeps_its_checkpoint_keys():
    config = AgentConfig(actor_hidden=(16,), critic_hidden=(16,))
    scale = [0.25, 2.0, 1.0, 0.05]
    scaled = MLPAgent(4, [0.5, 0.5], config, [0.0, 0.0], input_scale=scale)
    plain = MLPAgent(4, [0.5, 0.5], config, [0.0, 0.0])
    plain.load_state_dict(scaled.state_dict())  # the same keys: the scale is not saved
    obs = torch.randn(5, 4)
    state = scaled.initial_state(5)
    factor = torch.tensor(scale)
    assert torch.equal(scaled.actor(obs, state).mean, plain.actor(obs * factor, state).mean)
    assert torch.equal(scaled.value(obs, state), plain.value(obs * factor, state))
    assert observation_scale(["a_vel", "base_vel_x", "b"], {"base_*": 2.0, "*_vel": 0.5}) == [
        0.5, 2.0, 1.0]  # fmt: skip
    with pytest.raises(ValueError, match="input_scale"):
        MLPAgent(4, [0.5, 0.5], config, [0.0, 0.0], input_scale=[1.0])
    # a misspelled pattern scales nothing: refused, naming the entries
    with pytest.raises(ValueError, match=r"\['base_vel'\] match no entry.*'a_vel'"):
        observation_scale(["a_vel", "base_vel_x"], {"base_vel": 2.0, "*_vel": 0.5})


def test_a_saved_state_resumes_the_heading_command_exactly():
    env = recipe_env(3, command_resample_seconds=0.1)
    try:
        env.reset(seed=104)
        rng = np.random.default_rng(1)
        low, high = env.single_action_space.low, env.single_action_space.high
        middle = (low + high) / 2
        actions = [rng.uniform(low, high, (3, 12)) * 0.2 + 0.8 * middle for _ in range(40)]
        for action in actions[:10]:
            env.step(action)
        state = env.get_state()
        first = [env.step(action)[:2] for action in actions[10:]]
        env.set_state(state)
        again = [env.step(action)[:2] for action in actions[10:]]
        for (obs, reward), (obs2, reward2) in zip(first, again, strict=True):
            assert np.array_equal(obs, obs2) and np.array_equal(reward, reward2)
    finally:
        env.close()


def test_a_tiny_training_run_of_the_variant_completes(tmp_path):
    from cpg_actor.cli import main

    run = tmp_path / "run"
    code = main(["train", "--robot", "anymal", "--agent", "mlp", "--preset", "legged_gym",
                 "--total-steps", "2000", "--num-envs", "8", "--seed", "100",
                 "--run-dir", str(run), "--no-progress", "--set", "ppo.compile=false",
                 "--set", "eval_interval=0", "--set", "env.episode_seconds=1.0"])  # fmt: skip
    assert code in (0, None)
    assert (run / "checkpoints" / "last.pt").exists()
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    assert rows and all(math.isfinite(v) for v in rows[-1].values() if isinstance(v, float))
