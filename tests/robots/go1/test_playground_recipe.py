"""MuJoCo Playground's Go1 joystick recipe (``--preset playground``, the ``mlp-playground``
variant): each of its numbers beside its source, the reward's clip and field terms, the
uniform observation noise, the privileged critic, the command process and a tiny training."""

import json
import math

import numpy as np
import pytest
import torch

from cpg_actor.agents.base import AgentConfig
from cpg_actor.agents.mlp import MLPAgent
from cpg_actor.robots.common.quadruped.vector import hold_command, resample_command
from cpg_actor.robots.go1.config import Go1Config
from cpg_actor.robots.registry import get_robot
from cpg_actor.tasks import velocity as task
from cpg_actor_studies.reproduction import plan

JOYSTICK = "playground 0.2.0 go1/joystick.py default_config"
STEP = "playground 0.2.0 go1/joystick.py Joystick.step / _get_obs / sample_command"
RSL_RL = "playground 0.2.0 config/locomotion_params.py rsl_rl_config (Go1JoystickFlatTerrain)"
PARAMS = "playground 0.2.0 config/locomotion_params.py brax_ppo_config network_factory"
RANDOMIZE = "playground 0.2.0 go1/randomize.py domain_randomize"

# (the resolved config's value, the recipe's number, its source)
RECIPE = [
    ("env.kp", 35.0, JOYSTICK + " Kp"),
    ("env.kd", 0.5, JOYSTICK + " Kd"),
    ("env.action_scale", 0.5, JOYSTICK + " action_scale"),
    ("env.control_dt", 0.02, JOYSTICK + " ctrl_dt"),
    ("env.episode_steps", 1000, JOYSTICK + " episode_length"),
    ("env.soft_joint_limit_factor", 0.95, JOYSTICK + " soft_joint_pos_limit_factor"),
    ("env.observation_noise.joint_pos", 0.03, JOYSTICK + " noise_config.scales"),
    ("env.observation_noise.joint_vel", 1.5, JOYSTICK + " noise_config.scales"),
    ("env.observation_noise.gyro", 0.2, JOYSTICK + " noise_config.scales"),
    ("env.observation_noise.gravity", 0.05, JOYSTICK + " noise_config.scales"),
    ("env.observation_noise.lin_vel", 0.1, JOYSTICK + " noise_config.scales.linvel"),
    ("env.reward_scales.tracking_lin_vel", 1.0, JOYSTICK + " reward_config.scales"),
    ("env.reward_scales.tracking_ang_vel", 0.5, JOYSTICK + " reward_config.scales"),
    ("env.reward_scales.lin_vel_z_world", -0.5, JOYSTICK + " reward_config.scales.lin_vel_z"),
    ("env.reward_scales.ang_vel_xy_world", -0.05, JOYSTICK + " reward_config.scales.ang_vel_xy"),
    ("env.reward_scales.orientation", -5.0, JOYSTICK + " reward_config.scales"),
    ("env.reward_scales.dof_pos_limits", -1.0, JOYSTICK + " reward_config.scales"),
    ("env.reward_scales.pose", 0.5, JOYSTICK + " reward_config.scales"),
    ("env.reward_scales.termination", -1.0, JOYSTICK + " reward_config.scales"),
    ("env.reward_scales.stand_still", -1.0, JOYSTICK + " reward_config.scales"),
    ("env.reward_scales.torque_norms", -2e-4, JOYSTICK + " reward_config.scales.torques"),
    ("env.reward_scales.action_rate", -0.01, JOYSTICK + " reward_config.scales"),
    ("env.reward_scales.energy", -1e-3, JOYSTICK + " reward_config.scales"),
    ("env.reward_scales.feet_clearance", -2.0, JOYSTICK + " reward_config.scales"),
    ("env.reward_scales.feet_height", -0.2, JOYSTICK + " reward_config.scales"),
    ("env.reward_scales.feet_slip_commanded", -0.1, JOYSTICK + " reward_config.scales.feet_slip"),
    (
        "env.reward_scales.feet_air_time_commanded",
        0.1,
        JOYSTICK + " reward_config.scales.feet_air_time",
    ),
    ("env.tracking_sigma", 0.25, JOYSTICK + " reward_config.tracking_sigma"),
    ("env.max_foot_height", 0.1, JOYSTICK + " reward_config.max_foot_height"),
    ("env.air_time_target", 0.1, STEP + " _reward_feet_air_time (air_time - 0.1)"),
    ("env.leg_pose_weights", (1.0, 1.0, 0.1), STEP + " _reward_pose weight"),
    ("env.reward_clip_min", 0.0, STEP + " jp.clip(sum(rewards) * dt, 0.0, 10000.0)"),
    ("env.fall_tilt", math.pi / 2, STEP + " _get_termination: up-vector z < 0"),
    ("env.reset_noise", 0.0, STEP + " reset: qpos = the home keyframe"),
    ("env.floor_contacts", "feet", "playground 0.2.0 go1_constants.py FEET_ONLY_FLAT_TERRAIN_XML"),
    ("env.command_range", (-1.5, 1.5), JOYSTICK + " command_config.a[0]"),
    ("env.lateral_range", (-0.8, 0.8), JOYSTICK + " command_config.a[1]"),
    ("env.yaw_range", (-1.2, 1.2), JOYSTICK + " command_config.a[2]"),
    ("env.command_nonzero", (0.9, 0.25, 0.5), JOYSTICK + " command_config.b"),
    ("env.command_hold", 0.5, STEP + " sample_command: w ~ bernoulli(0.5)"),
    ("env.command_resample_seconds", 5.0, STEP + " exponential(key) * 5.0"),
    ("env.command_interval", "exponential", STEP + " exponential(key) * 5.0"),
    ("env.standing_share", 0.0, STEP + " reset: uniform in [-a, a], never zeroed"),
    ("env.observe_lin_vel", True, STEP + " _get_obs state: noisy_linvel first"),
    ("env.privileged_observation", True, PARAMS + " value_obs_key privileged_state"),
    ("env.randomize.friction", (0.4, 1.0), RANDOMIZE + " floor friction"),
    ("env.randomize.armature", (1.0, 1.05), RANDOMIZE + " armature"),
    ("env.randomize.payload", (0.0, 1.0), RANDOMIZE + " torso mass + U(-1, 1), its >= 0 half"),
    ("agent", "mlp", RSL_RL + " policy.class_name ActorCritic"),
    ("agent_config.actor_hidden", (512, 256, 128), RSL_RL + " actor_hidden_dims"),
    ("agent_config.critic_hidden", (512, 256, 128), RSL_RL + " critic_hidden_dims"),
    ("agent_config.activation", "elu", RSL_RL + " activation"),
    ("agent_config.init_std", 1.0, RSL_RL + " init_noise_std"),
    ("ppo.num_steps", 24, RSL_RL + " num_steps_per_env"),
    ("ppo.num_epochs", 5, RSL_RL + " num_learning_epochs"),
    ("ppo.num_minibatches", 4, RSL_RL + " num_mini_batches"),
    ("ppo.learning_rate", 3e-4, RSL_RL + " learning_rate (Go1JoystickFlatTerrain)"),
    ("ppo.lr_schedule", "fixed", RSL_RL + " schedule (Go1JoystickFlatTerrain)"),
    ("ppo.entropy_coef", 0.001, RSL_RL + " entropy_coef"),
    ("ppo.gamma", 0.99, RSL_RL + " gamma"),
    ("ppo.gae_lambda", 0.95, RSL_RL + " lam"),
    ("ppo.clip_ratio", 0.2, RSL_RL + " clip_param"),
    ("ppo.clip_value_loss", True, RSL_RL + " use_clipped_value_loss"),
    ("ppo.value_loss_coef", 1.0, RSL_RL + " value_loss_coef"),
    ("ppo.max_grad_norm", 1.0, RSL_RL + " max_grad_norm"),
    ("ppo.normalize_observations", True, RSL_RL + " empirical_normalization"),
    ("ppo.normalize_rewards", False, RSL_RL + " (rsl_rl scales no reward)"),
]


@pytest.fixture(scope="module")
def recipe():
    settings = plan.ReproduceSettings(["mlp-playground"], 1, 100_000, overrides=["robot=go1"],
                                      first_seed=100)  # fmt: skip
    return plan.resolve_config(settings, "mlp-playground")


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
    else:
        assert value == number, source


def test_the_variant_is_the_recipe_whatever_the_reproductions_preset(recipe):
    """mlp-playground runs under its own recipe, also beside variants of another (omni)."""
    assert (recipe.robot, recipe.preset) == ("go1", "playground")
    omni = plan.ReproduceSettings(["mlp-playground", "mlp-field"], 1, 100_000,
                                  overrides=["robot=go1"], preset="omni")  # fmt: skip
    assert plan.resolve_config(omni, "mlp-playground").to_dict() == recipe.to_dict()
    assert plan.resolve_config(omni, "mlp-field").preset == "omni"
    tasks = plan.build_tasks(omni, plan.Path("/tmp/unused"), workers=1)
    args = {task.variant: task.train_args for task in tasks}
    preset_of = {v: a[a.index("--preset") + 1] for v, a in args.items()}
    assert preset_of == {"mlp-playground": "playground", "mlp-field": "omni"}
    # the project's own terms are not paid (Playground defines its own of those names)
    own = {"lin_vel_z", "ang_vel_xy", "base_height", "torques", "joint_acc", "feet_air_time",
           "feet_slip"}  # fmt: skip
    assert all(recipe.env.reward_scales[name] == 0.0 for name in own)


def test_the_recipe_is_the_go1s_and_the_mlps_alone():
    from cpg_actor.config import compose_config

    with pytest.raises(ValueError, match="has no PLAYGROUND"):
        compose_config("playground", values={"robot": "anymal", "agent": "mlp"})
    with pytest.raises(ValueError, match="privileged_observation"):
        compose_config("playground", values={"robot": "go1", "agent": "cpg-actor"})
    with pytest.raises(ValueError, match="MuJoCo's only"):
        Go1Config(sim="mjx", observe_lin_vel=True).validate()
    with pytest.raises(ValueError, match="observation_noise"):
        Go1Config(observation_noise={"joint_pos": -0.1}).validate()
    with pytest.raises(ValueError, match="command_nonzero"):
        Go1Config(command_nonzero=(0.5, 2.0, 0.5)).validate()


def recipe_env(num_envs: int, **changes):
    """The Go1's env under the recipe (without its randomisation), ``changes`` made."""
    values = {k: v for k, v in Go1Config.PLAYGROUND.items() if k != "randomize"}
    config = Go1Config.from_dict({**values, **changes})
    return get_robot("go1").make(num_envs, config, 1)


def test_actions_are_the_home_pose_plus_half_a_radian_at_most():
    env = recipe_env(2)
    try:
        home = np.asarray(env.robot.nominal_pose)
        space = env.single_action_space
        assert np.allclose(space.low, home - 0.5, rtol=1e-6)
        assert np.allclose(space.high, home + 0.5, rtol=1e-6)
        names = env.robot.observation_names
        assert names[45:48] == task.LIN_VEL_NAMES and task.actor_entries(names) == 48
    finally:
        env.close()


def test_the_clipped_reward_of_a_falling_robot_is_never_negative():
    """Legs thrown about make the robot fall; every step's reward is >= 0 although its terms
    sum below 0 (the clip acts), and the fall's step pays the termination term."""
    env = recipe_env(4)
    try:
        env.reset(seed=100)
        rng = np.random.default_rng(0)
        low, high = env.single_action_space.low, env.single_action_space.high
        rewards, sums, fell = [], [], False
        for _ in range(400):
            _, reward, terminated, _, info = env.step(rng.uniform(low, high, (4, 12)))
            rewards.append(reward)
            sums.append(sum(info["reward_terms"].values()))
            if terminated.any():
                fell = True
                assert (info["reward_terms"]["termination"][terminated] < 0).all()
        assert fell
        assert (np.concatenate(rewards) >= 0.0).all()
        assert (np.concatenate(sums) < 0.0).any()
    finally:
        env.close()


def field(**given):
    """:func:`task.field_terms` for 1 robot at its nominal pose, standing, ``given`` replaced."""
    nominal = np.array([0.0, 0.9, -1.8] * 4)
    inputs = dict(
        quat=np.array([[1.0, 0, 0, 0]]), lin_vel=np.zeros((1, 3)), ang_vel=np.zeros((1, 3)),
        command=np.array([[0.5, 0.0, 0.0]]), joint_pos=nominal[None].copy(),
        joint_vel=np.zeros((1, 12)), torque=np.zeros((1, 12)),
        terminated=np.array([False]), feet_z=np.full((1, 4), 0.02),
        feet_speed=np.zeros((1, 4, 2)), contact=np.ones((1, 4), bool),
        touchdown=np.zeros((1, 4), bool), air_time=np.zeros((1, 4)),
        swing_peak=np.zeros((1, 4)), nominal=nominal, pose_weights=np.array([1, 1, 0.1] * 4),
        joint_range=None, max_foot_height=0.1, air_time_target=0.1,
    )  # fmt: skip
    inputs.update(given)
    return {name: float(value[0]) for name, value in task.field_terms(**inputs).items()}


def test_feet_air_time_pays_only_at_a_touchdown_after_time_in_the_air():
    landing = np.array([[True, False, False, False]])
    air = np.array([[0.3, 0.3, 0.0, 0.0]])
    assert field(air_time=air)["feet_air_time_commanded"] == 0.0  # in the air, no touchdown
    assert field(air_time=air, touchdown=landing)["feet_air_time_commanded"] == pytest.approx(
        0.3 - 0.1, rel=1e-9)  # fmt: skip
    assert field(air_time=np.array([[0.04, 0, 0, 0]]), touchdown=landing)[
        "feet_air_time_commanded"
    ] == pytest.approx(0.04 - 0.1, rel=1e-9)  # a short hop costs
    still = np.zeros((1, 3))  # no air time paid under a zero command
    assert field(air_time=air, touchdown=landing, command=still)["feet_air_time_commanded"] == 0


def test_the_field_terms_measure_what_playground_measures():
    nominal = np.array([0.0, 0.9, -1.8] * 4)
    assert field()["pose"] == pytest.approx(1.0, rel=1e-12)
    bent = nominal.copy()
    bent[2] += 0.5  # a knee: weight 0.1
    assert field(joint_pos=bent[None])["pose"] == pytest.approx(math.exp(-0.025), rel=1e-9)
    assert field(joint_pos=bent[None])["stand_still"] == 0.0  # commanded to move
    assert field(joint_pos=bent[None], command=np.zeros((1, 3)))["stand_still"] == pytest.approx(
        0.5, rel=1e-9)  # fmt: skip
    limits = (nominal - 0.2, nominal + 0.2)
    assert field(joint_pos=bent[None], joint_range=limits)["dof_pos_limits"] == pytest.approx(
        0.3, rel=1e-9)  # fmt: skip
    torque = np.array([[3.0, 4.0] + [0.0] * 10])
    assert field(torque=torque)["torque_norms"] == pytest.approx(5.0 + 7.0, rel=1e-12)
    speed = np.array([[[0.3, 0.4], [0, 0], [0, 0], [0, 0]]])  # one foot at 0.5 m/s
    assert field(feet_speed=speed)["feet_slip_commanded"] == pytest.approx(0.25, rel=1e-9)
    clearance = field(feet_speed=speed)["feet_clearance"]  # |0.02 - 0.1| sqrt(0.5)
    assert clearance == pytest.approx(0.08 * math.sqrt(0.5), rel=1e-9)
    peak = np.array([[0.05, 0, 0, 0]])
    landing = np.array([[True, False, False, False]])
    assert field(swing_peak=peak, touchdown=landing)["feet_height"] == pytest.approx(
        0.25, rel=1e-9)  # (0.05 / 0.1 - 1)^2  # fmt: skip
    # a base pitched 90 degrees: its own forward velocity is the world's vertical one
    pitched = np.array([[math.cos(math.pi / 4), 0.0, -math.sin(math.pi / 4), 0.0]])
    forward = np.array([[1.0, 0.0, 0.0]])
    assert field(quat=pitched, lin_vel=forward)["lin_vel_z_world"] == pytest.approx(1.0, rel=1e-9)
    assert field(terminated=np.array([True]))["termination"] == 1.0


def test_the_observation_noise_is_uniform_of_the_stated_half_widths():
    """The actor's entries differ from the privileged (noise-free) copies of the same
    quantities by noise within +-w whose spread is a uniform's, w / sqrt(3)."""
    env = recipe_env(8)
    try:
        env.reset(seed=101)
        names = env.robot.observation_names
        column = {name: i for i, name in enumerate(names)}
        groups = {
            "gyro": [f"base_ang_vel_{a}" for a in "xyz"],
            "gravity": [f"projected_gravity_{a}" for a in "xyz"],
            "lin_vel": [f"base_lin_vel_{a}" for a in "xyz"],
            "joint_pos": [f"{j}_pos" for j in env.robot.joint_names],
            "joint_vel": [f"{j}_vel" for j in env.robot.joint_names],
        }
        noise = {group: [] for group in groups}
        home = np.tile(np.asarray(env.robot.nominal_pose), (8, 1))
        for _ in range(40):
            obs, *_ = env.step(home)
            for group, entries in groups.items():
                actor = obs[:, [column[n] for n in entries]]
                truth = obs[:, [column[task.PRIVILEGED_PREFIX + n] for n in entries]]
                noise[group].append(actor - truth)
        for group, width in Go1Config.PLAYGROUND["observation_noise"].items():
            drawn = np.concatenate(noise[group]).ravel()
            assert np.abs(drawn).max() <= width * (1 + 1e-4) + 1e-6, group
            assert drawn.std() == pytest.approx(width / math.sqrt(3), rel=0.15), group
            assert abs(drawn.mean()) < 0.15 * width, group
    finally:
        env.close()


def test_the_mlps_actor_does_not_see_the_privileged_entries():
    config = AgentConfig(actor_hidden=(16,), critic_hidden=(16,))
    agent = MLPAgent(10, [0.5] * 2, config, [0.0, 0.0], actor_obs=6)
    obs = torch.randn(3, 10)
    other = obs.clone()
    other[:, 6:] += 1.0  # the privileged entries changed
    state = agent.initial_state(3)
    assert torch.equal(agent.actor(obs, state).mean, agent.actor(other, state).mean)
    assert not torch.equal(agent.value(obs, state), agent.value(other, state))
    with pytest.raises(ValueError, match="actor_obs"):
        MLPAgent(10, [0.5] * 2, config, [0.0, 0.0], actor_obs=11)


def test_playgrounds_command_process():
    previous = np.array([1.0, -0.5, 0.7])
    fresh = np.array([0.2, 0.3, -0.4])
    hold = np.array([True, False, False])
    nonzero = np.array([False, True, False])
    assert hold_command(previous, fresh, hold, nonzero).tolist() == [1.0, 0.3, 0.0]
    config = Go1Config.from_dict(dict(Go1Config.PLAYGROUND))
    rng = np.random.default_rng(7)
    draws = np.array([resample_command(rng, previous, config) for _ in range(4000)])
    kept = (draws == previous).mean(axis=0)
    zero = (draws == 0.0).mean(axis=0)
    # kept with 0.5; else zeroed with 1 - b
    assert kept == pytest.approx([0.5] * 3, rel=0.08)
    assert zero == pytest.approx(0.5 * (1 - np.array([0.9, 0.25, 0.5])), rel=0.12)
    assert (np.abs(draws) <= [1.5, 0.8, 1.2]).all()


def test_a_tiny_training_run_of_the_variant_completes(tmp_path):
    from cpg_actor.cli import main

    run = tmp_path / "run"
    code = main(["train", "--robot", "go1", "--agent", "mlp", "--preset", "playground",
                 "--total-steps", "2000", "--num-envs", "8", "--seed", "100",
                 "--run-dir", str(run), "--no-progress", "--set", "ppo.compile=false",
                 "--set", "eval_interval=0", "--set", "env.episode_seconds=1.0"])  # fmt: skip
    assert code in (0, None)
    assert (run / "checkpoints" / "last.pt").exists()
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    assert rows and all(math.isfinite(v) for v in rows[-1].values() if isinstance(v, float))


def test_mlp_warm_trains_on_the_recipe_its_actor_without_the_privileged_entries(tmp_path):
    """mlp-warm (the MLP cloned from the CPG's trot, then PPO) has the MLP's privileged critic:
    the cloning and PPO run on the recipe, and its actor reads the actor's entries alone."""
    from cpg_actor.cli import main
    from cpg_actor.config import compose_config
    from cpg_actor.deploy import load_policy

    run = tmp_path / "run"
    code = main(["train", "--robot", "go1", "--agent", "mlp-warm", "--preset", "playground",
                 "--total-steps", "192", "--num-envs", "4", "--seed", "100",
                 "--run-dir", str(run), "--no-progress", "--set", "ppo.compile=false",
                 "--set", "eval_interval=0", "--set", "env.episode_seconds=1.0",
                 "--set", "warm_start.epochs=2",
                 "--set", "warm_start.rollout_steps=20"])  # fmt: skip
    assert code in (0, None)
    losses = json.loads((run / "warm_start.json").read_text())["loss"]
    assert len(losses) == 2 and all(math.isfinite(v) for v in losses)
    policy = load_policy(run)
    names = policy.robot.observation_names
    assert policy.actor_obs_dim == task.actor_entries(names) < policy.obs_dim
    assert policy.agent.actor_mlp[0].in_features == policy.actor_obs_dim
    with pytest.raises(ValueError, match="agents that have one: mlp, mlp-warm"):
        compose_config("playground", values={"robot": "go1", "agent": "cpg-actor"})


def test_a_saved_state_resumes_the_recipes_env_exactly():
    """The command clock, the feet's swing peaks and the noise's generators are in the state:
    the steps after set_state are the steps after get_state."""
    env = recipe_env(3, command_resample_seconds=0.1)  # a new command every few steps
    try:
        env.reset(seed=102)
        rng = np.random.default_rng(1)
        low, high = env.single_action_space.low, env.single_action_space.high
        actions = [
            rng.uniform(low, high, (3, 12)) * 0.2 + 0.8 * (low + high) / 2 for _ in range(60)
        ]
        for action in actions[:20]:
            env.step(action)
        state = env.get_state()
        commands = env.command.copy()
        first = [env.step(action)[:2] for action in actions[20:]]
        assert not np.array_equal(commands, env.command)  # drawn again meanwhile
        env.set_state(state)
        again = [env.step(action)[:2] for action in actions[20:]]
        for (obs, reward), (obs2, reward2) in zip(first, again, strict=True):
            assert np.array_equal(obs, obs2) and np.array_equal(reward, reward2)
    finally:
        env.close()
