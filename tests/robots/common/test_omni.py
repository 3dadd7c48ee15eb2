"""The quadrupeds' omnidirectional task and the command in the CPG's prior: commands drawn
again within an episode (``command_resample_seconds``) with a share standing still, on both
robots; the ``omni`` recipe; the planar drive (each leg's drive and step direction from the
command) and the foot-space pattern's planar steps, checked against MuJoCo's kinematics; the
forward task and the forward drive unchanged; bad input."""

import math

import numpy as np
import pytest
import torch

from cpg_actor.agents.base import AgentConfig
from cpg_actor.agents.cpg_actor import CPGActorAgent
from cpg_actor.config import compose_config
from cpg_actor.robots.common import mjx_runtime as runtime
from cpg_actor.robots.common.mujoco_runtime import mujoco
from cpg_actor.robots.plugin import load
from cpg_actor.robots.registry import get_robot

QUADRUPEDS = ("go1", "anymal")


def omni_env(name: str, num_envs: int, **changes):
    robot = get_robot(name)
    config = robot.config_class(**robot.config_class.OMNI_COMMANDS).replace(**changes)
    return robot.make(num_envs, config, num_threads=1)


@pytest.mark.parametrize("name", QUADRUPEDS)
def test_commands_are_drawn_again_at_each_period_within_the_ranges_some_standing(name):
    """Every 5 steps (0.1 s) each env draws a new command: the observation after the step that
    draws it shows it, the next step runs under it (info["command"]); in between the command
    holds. Each draw lies in the ranges, both signs of each axis come, and about the standing
    share of them (here a half) are zero."""
    env = omni_env(name, 8, command_resample_seconds=0.1, standing_share=0.5,
                   episode_seconds=2.0)  # fmt: skip
    assert env.config.resample_steps == 5
    obs, info = env.reset(seed=0)
    draws, shown = [info["command"].copy()], obs[:, 6:9].copy()
    pose = np.tile(np.asarray(env.quadruped.nominal_pose), (8, 1))
    for step in range(1, 31):
        obs, _, terminated, truncated, info = env.step(pose)
        assert not (terminated | truncated).any()
        np.testing.assert_array_equal(info["command"], draws[-1])  # the step ran under it
        if step % 5 == 0:
            assert np.all(np.any(obs[:, 6:9] != shown, axis=1) | np.all(shown == 0, axis=1))
            draws.append(env.command.copy())
        np.testing.assert_allclose(obs[:, 6:9], draws[-1], rtol=1e-6)  # float32 observation
        shown = obs[:, 6:9].copy()
    commands = np.concatenate(draws)  # 7 draws of 8 envs
    config = env.config
    for column, (low, high) in enumerate((config.command_range, config.lateral_range,
                                          config.yaw_range)):  # fmt: skip
        values = commands[:, column]
        assert np.all((low <= values) & (values <= high))
        assert values.min() < 0.5 * low and values.max() > 0.5 * high  # both signs, spread
    standing = np.all(commands == 0.0, axis=1).mean()
    assert 0.25 < standing < 0.75
    env.close()


def test_the_forward_task_stays_the_default_one_command_per_episode():
    """The robots' defaults are the forward task (a forward command per episode, no lateral or
    yaw command, never resampled, none standing), and a run under them draws as before: the
    same first observations as a config naming the new fields at their defaults."""
    for name in QUADRUPEDS:
        config = get_robot(name).config_class()
        assert (tuple(config.command_range), tuple(config.lateral_range),
                tuple(config.yaw_range)) == ((0.0, 1.0), (0.0, 0.0), (0.0, 0.0))  # fmt: skip
        assert (config.resample_steps, config.standing_share) == (0, 0.0)
    robot = get_robot("go1")
    plain = robot.make(2, robot.config_class(), num_threads=1)
    named = robot.make(2, robot.config_class(command_resample_seconds=None), num_threads=1)
    first, _ = plain.reset(seed=4)
    np.testing.assert_array_equal(first, named.reset(seed=4)[0])
    pose = np.tile(np.asarray(plain.quadruped.nominal_pose), (2, 1))
    for _ in range(60):
        obs, *_ = plain.step(pose)
        np.testing.assert_array_equal(obs[:, 6:9], first[:, 6:9])  # held all episode
    plain.close(), named.close()


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"command_range": ()}, r"command_range must be \[low, high\] in m/s with low <= high"),
        ({"command_range": (1.0, -1.0)}, "command_range must be .* low <= high"),
        ({"lateral_range": (0.5, -0.5)}, "lateral_range must be .* low <= high"),
        ({"yaw_range": (1.0,)}, r"yaw_range must be \[low, high\] in rad/s"),
        ({"command_resample_seconds": -1.0}, "command_resample_seconds must be .* >= 0"),
        ({"command_resample_seconds": float("nan")}, "command_resample_seconds must be"),
        ({"standing_share": 1.5}, r"standing_share must be a number in \[0, 1\]"),
        ({"standing_share": -0.1}, r"standing_share must be a number in \[0, 1\]"),
    ],
)
def test_bad_commands_say_which_field_and_what_is_accepted(change, message):
    with pytest.raises(ValueError, match=message) as error:
        get_robot("go1").config_class().replace(**change)
    assert "\n" not in str(error.value)


def test_the_omni_recipe_takes_the_robots_own_commands_and_planar_steps():
    """``--robot go1 --preset omni``: the throughput recipe, the Go1's OMNI_COMMANDS and the
    planar drive; the hopper has no such task (one line)."""
    config = compose_config(preset="omni", values={"robot": "go1"})
    expected = get_robot("go1").config_class.OMNI_COMMANDS
    assert {k: getattr(config.env, k) for k in expected} == expected
    assert config.agent_config.cpg_planar_steps and config.agent_config.cpg_layout == "leg"
    assert (config.num_envs, config.ppo.lr_schedule) == (256, "adaptive")
    assert compose_config(values={"robot": "go1"}).env.lateral_range == (0.0, 0.0)
    with pytest.raises(ValueError, match="preset 'omni' is a task this robot does not define"):
        compose_config(preset="omni", values={"robot": "hopper"})


# -- the prior ---------------------------------------------------------------------------------


def layout(name: str):
    return get_robot(name).cpg_layouts()["leg"]


def test_the_planar_drive_of_a_forward_command_is_the_forward_drive():
    """(v, 0, 0) with v >= 0: every leg's drive v, direction 0 (exactly)."""
    drive, direction = (
        layout("go1")
        .planar_drive()
        .double()(
            torch.tensor([[0.0, 0.0, 0.0], [0.7, 0.0, 0.0], [1.0, 0.0, 0.0]], dtype=torch.float64)
        )
    )
    assert torch.equal(drive, torch.tensor([0.0, 0.7, 1.0], dtype=torch.float64)[:, None]
                       .expand(3, 4))  # fmt: skip
    assert torch.equal(direction, torch.zeros(3, 4, dtype=torch.float64))


@pytest.mark.parametrize("name", QUADRUPEDS)
def test_the_step_direction_follows_the_command(name):
    """Left: every leg steps along +y; backward: along -x; turning left (counter-clockwise):
    the left feet step backward and the right feet forward, each foot at the yaw rate times
    its distance from the base's centre."""
    drive_of = layout(name).planar_drive().double()
    commands = torch.tensor([[0.0, 0.3, 0.0], [-0.5, 0.0, 0.0], [0.0, 0.0, 0.8]],
                            dtype=torch.float64)  # fmt: skip
    drive, direction = drive_of(commands)
    torch.testing.assert_close(direction[0], torch.full((4,), math.pi / 2, dtype=torch.float64))
    torch.testing.assert_close(drive[0], torch.full((4,), 0.3, dtype=torch.float64))
    torch.testing.assert_close(direction[1].abs(), torch.full((4,), math.pi, dtype=torch.float64))
    feet = drive_of.feet
    left = feet[:, 1] > 0
    forward = torch.cos(direction[2])  # the step's forward share
    assert torch.all(forward[left] < 0) and torch.all(forward[~left] > 0)
    torch.testing.assert_close(drive[2], 0.8 * feet.norm(dim=1))


def quadruped(name: str):
    """The robot's QuadrupedModel (its MuJoCo env's)."""
    return load(get_robot(name).make.args[0]).quadruped


def foot_sites(name: str, joints: np.ndarray) -> np.ndarray:
    """(4, 3) the foot centres in the base frame under ``joints`` (12,), MuJoCo's kinematics of
    the robot's own MJCF (an independent reference)."""
    quadruped = load(get_robot(name).make.args[0]).quadruped
    model = mujoco.MjModel.from_xml_string(quadruped.mjcf_text(None))
    data = mujoco.MjData(model)
    data.qpos[3] = 1.0
    data.qpos[7:] = joints
    mujoco.mj_kinematics(model, data)
    return np.array([data.site(f"{leg}_foot").xpos for leg in quadruped.legs])


@pytest.mark.parametrize("name", QUADRUPEDS)
def test_planar_steps_put_each_foot_along_its_direction(name):
    """At the end of a swing (phase pi: the step's front end, no lift) the pattern's joints put
    every foot r along its direction in the ground plane, by MuJoCo's kinematics of the robot:
    forward, left, backward, right and a diagonal."""
    nominal = np.asarray(quadruped(name).nominal_pose)
    pattern = layout(name).pattern(tuple(nominal)).double()
    home = foot_sites(name, nominal)
    r = 0.05
    phase = torch.full((1, 4), math.pi, dtype=torch.float64)
    amplitude = torch.full((1, 4), r, dtype=torch.float64)
    for psi in (0.0, math.pi / 2, math.pi, -math.pi / 2, math.pi / 4):
        direction = torch.full((1, 4), psi, dtype=torch.float64)
        joints = pattern(phase, amplitude, direction)[0].numpy()
        moved = foot_sites(name, joints) - home
        expected = np.tile([r * math.cos(psi), r * math.sin(psi), 0.0], (4, 1))
        np.testing.assert_allclose(moved, expected, atol=1e-6, err_msg=f"{name} psi={psi}")
    # direction 0 is the forward pattern
    zero = torch.zeros(1, 4, dtype=torch.float64)
    torch.testing.assert_close(pattern(phase, amplitude, zero), pattern(phase, amplitude))


def test_the_cpg_actor_with_planar_steps_acts_as_the_forward_one_on_a_forward_command():
    """Same weights: on a forward command the planar drive gives the forward agent's action
    (the state has a direction row more); on a left command the feet step sideways (the
    abduction joints move) where the forward agent's stay at the nominal pose."""
    robot = get_robot("go1")
    env = robot.make(2, robot.config_class(), num_threads=1)
    obs, _ = env.reset(seed=0)
    obs = torch.as_tensor(obs)
    obs[:, 6:9] = torch.tensor([[0.6, 0.0, 0.0], [0.0, 0.4, 0.0]])
    agents = []
    for planar in (False, True):
        torch.manual_seed(0)
        config = AgentConfig(cpg_layout="leg", cpg_planar_steps=planar)
        agents.append(CPGActorAgent(45, [1.0] * 12, config, env.robot, robot))
    forward, planar = agents
    assert planar.state_rows[-2:] == ("drive", "direction") and planar.state_shape == (7, 4)
    means = []
    for agent in agents:
        state = agent.observe(obs, agent.initial_state(2))
        for _ in range(10):
            out = agent.actor(obs, state)
            state = agent.observe(obs, out.next_state)
        means.append(out.mean)
    torch.testing.assert_close(means[1][0], means[0][0], rtol=1e-5, atol=1e-5)
    abduction = means[1][1, 0::3]
    assert abduction.abs().max() > 0.01 and torch.all(means[0][1, 0::3] == 0.0)
    with pytest.raises(ValueError, match="cpg_planar_steps needs a CPG layout with planar"):
        CPGActorAgent(
            45, [1.0] * 12, AgentConfig(cpg_layout="joint", cpg_planar_steps=True), env.robot, robot
        )
    env.close()


@pytest.mark.slow
def test_the_mjx_env_draws_commands_again_as_the_mujoco_env():
    """MJX: the same period, ranges and standing share (other numbers than MuJoCo's)."""
    if not runtime.available():
        pytest.skip('the MJX backend needs pip install -e ".[mjx]"')
    from cpg_actor.robots.go1.mjx import MjxGo1VectorEnv

    config = {
        **get_robot("go1").config_class.OMNI_COMMANDS,
        "sim": "mjx",
        "reset_noise": 0.0,
        "episode_seconds": 1.0,
        "command_resample_seconds": 0.1,
        "standing_share": 0.5,
    }
    env = MjxGo1VectorEnv(4, config)
    obs, info = env.reset(seed=0)
    draws, pose = [info["command"]], np.tile(np.asarray(env.quadruped.nominal_pose), (4, 1))
    for step in range(1, 16):
        obs, _, terminated, truncated, info = env.step(pose)
        np.testing.assert_allclose(info["command"], draws[-1])
        if step % 5 == 0:
            assert not np.allclose(obs[:, 6:9], draws[-1])
            draws.append(obs[:, 6:9].copy())
        np.testing.assert_allclose(obs[:, 6:9], draws[-1])
    commands = np.concatenate(draws)
    assert np.all(np.abs(commands) <= [1.0, 0.5, 1.0]) and np.all(commands == 0, axis=1).any()
    env.close()


def test_a_leg_layout_checkpoint_from_before_planar_steps_loads_into_either_agent():
    """The planar geometry (each foot's place, its lateral offset) is the robot's, not learned:
    out of the state dict, so a checkpoint saved before planar steps existed loads, and one of
    a planar agent carries the same learned tensors as a forward one."""
    robot = get_robot("go1")
    env = robot.make(1, robot.config_class(), num_threads=1)
    agents = [
        CPGActorAgent(45, [1.0] * 12, AgentConfig(cpg_layout="leg", cpg_planar_steps=planar),
                      env.robot, robot)
        for planar in (False, True)
    ]  # fmt: skip
    env.close()
    saved = agents[0].state_dict()
    assert not any(key.endswith(("lateral", "feet")) for key in saved)
    assert set(agents[1].state_dict()) == set(saved)
    for agent in agents:
        agent.load_state_dict(saved)  # strict
