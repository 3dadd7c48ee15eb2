"""The quadrupeds' evaluation protocol: the velocity task's tracking metrics (linear velocity
error, yaw-rate error, duty factor, planar cost of transport) on hand-made readings, the grid's
commands held for whole episodes, `cpg-actor eval RUN --grid` on a tiny trained Go1 run (its
table printed and saved, the payload and push checks), and bad input."""

import csv
import json
import math

import numpy as np
import pytest

from cpg_actor.cli import main
from cpg_actor.robots.registry import get_robot
from cpg_actor.robustness import protocol
from cpg_actor.tasks import velocity as task


def walk(command, lin_vel, yaw_rate, contact, steps=5, n=1):
    """The episode metrics of ``steps`` control steps (0.02 s) of hand-made readings: the base
    moving at ``lin_vel`` (base frame) and turning at ``yaw_rate`` (or ``yaw_rate(step)``),
    level, the feet on the ground where ``contact`` (4 bool), the joints doing 1 J of work per
    step."""
    config = get_robot("go1").config_class(episode_seconds=steps * 0.02)
    nominal = np.zeros(12)
    joints = np.zeros((n, 12))
    feet = np.zeros((n, 4, 3))
    feet[:, :, 2] = np.where(contact, 0.02, 0.2)  # the Go1's foot radius is 0.023 m
    command = np.tile(np.asarray(command, dtype=float), (n, 1))
    episode = task.new_episode(command, joints, np.zeros(n), feet[:, :, :2].copy())
    for step in range(1, steps + 1):
        qpos = np.zeros((n, 19))
        qpos[:, 2], qpos[:, 3] = 0.3, 1.0  # standing height, level
        qvel = np.zeros((n, 18))
        reading = task.Reading(
            qpos=qpos, qvel=qvel, lin_vel=np.tile([*lin_vel, 0.0], (n, 1)),
            ang_vel=np.tile([0.0, 0.0, yaw_rate(step) if callable(yaw_rate) else yaw_rate],
                            (n, 1)), feet=feet, torque=np.zeros((n, 12)),
            work=np.full(n, 1.0), base_touch=np.zeros(n, bool), unstable=np.zeros(n, bool),
        )  # fmt: skip
        episode, out = task.step(config, episode, reading, joints, nominal, 0.023, 100.0)
    assert out["truncated"].all()
    return {name: float(value[0]) for name, value in out["episode_metrics"].items()}


def test_a_robot_walking_exactly_at_its_command_has_no_error():
    metrics = walk((0.5, 0.2, 0.3), (0.5, 0.2), 0.3, [True] * 4)
    for name in ("lin_vel_error", "yaw_rate_error", "lin_vel_offset", "yaw_rate_offset"):
        assert metrics[name] == pytest.approx(0.0, abs=1e-12)
    assert metrics["duty_factor"] == pytest.approx(1.0)


def test_the_errors_are_distances_whatever_the_sign():
    """|v_xy - command_xy| in the plane (a 3-4-5 triangle) and |yaw rate - command|: a turn
    too slow to the left errs as much as one too fast to the right."""
    metrics = walk((0.5, 0.0, 0.5), (0.2, -0.4), 0.0, [True] * 4)
    assert metrics["lin_vel_error"] == pytest.approx(0.5, rel=1e-9)
    assert metrics["yaw_rate_error"] == pytest.approx(0.5, rel=1e-9)
    left = walk((0.0, 0.0, 1.0), (0.0, 0.0), 0.7, [True] * 4)["yaw_rate_error"]
    right = walk((0.0, 0.0, -1.0), (0.0, 0.0), -1.3, [True] * 4)["yaw_rate_error"]
    assert left == pytest.approx(0.3, rel=1e-9) and right == pytest.approx(0.3, rel=1e-9)
    assert walk((0.0, 0.0, 0.0), (0.0, 0.0), -0.2, [True] * 4)["yaw_rate_error"] == (
        pytest.approx(walk((0.0, 0.0, 0.0), (0.0, 0.0), 0.2, [True] * 4)["yaw_rate_error"])
    )
    # a constant error: the offset (the error of the mean) is the error
    assert metrics["lin_vel_offset"] == pytest.approx(0.5, rel=1e-9)
    assert metrics["yaw_rate_offset"] == pytest.approx(0.5, rel=1e-9)
    # the forward-only metric stays what it was: the forward speed's error alone
    assert metrics["speed_error"] == pytest.approx(0.3, rel=1e-9)


def test_a_sway_about_the_command_errs_at_each_step_but_has_no_offset():
    """A trot rocks the base's yaw: +-0.4 rad/s about a 0.5 rad/s turn, step by step, is a
    yaw-rate error of 0.4 and an offset of 0 (the turn itself is right)."""
    metrics = walk((0.0, 0.0, 0.5), (0.0, 0.0), lambda step: 0.5 + 0.4 * (-1) ** step,
                   [True] * 4, steps=6)  # fmt: skip
    assert metrics["yaw_rate_error"] == pytest.approx(0.4, rel=1e-9)
    assert metrics["yaw_rate_offset"] == pytest.approx(0.0, abs=1e-12)


def test_duty_factor_and_the_planar_cost_of_transport():
    """Two feet of four on the ground all episode: a duty factor of a half. A base walking
    sideways at 0.3 m/s for 0.4 s (0.12 m, none forward) has a planar cost of transport, work /
    (m g d), where the forward one is undefined; one whose path is under 0.1 m has none."""
    metrics = walk((0.0, 0.3, 0.0), (0.0, 0.3), 0.0, [True, False, False, True], steps=20)
    assert metrics["duty_factor"] == pytest.approx(0.5)
    assert metrics["planar_cost_of_transport"] == pytest.approx(20 * 1.0 / (100.0 * 0.12))
    assert math.isnan(metrics["cost_of_transport"])
    short = walk((0.0, 0.3, 0.0), (0.0, 0.3), 0.0, [True] * 4, steps=10)  # 0.06 m
    assert math.isnan(short["planar_cost_of_transport"])


def test_a_grid_command_is_held_for_the_whole_episode():
    """The env of a grid row runs every env under its command from reset to the end, never
    drawn again, none standing, even from the omnidirectional task's ranges."""
    robot = get_robot("go1")
    omni = robot.config_class(**robot.config_class.OMNI_COMMANDS, episode_seconds=0.3)
    command = protocol.GRID[10]  # combined
    env = robot.make(3, protocol.command_env(omni, command), num_threads=1)
    obs, info = env.reset(seed=3)
    np.testing.assert_allclose(info["command"], np.tile(command.values, (3, 1)))
    pose = np.tile(np.asarray(env.quadruped.nominal_pose), (3, 1))
    for _ in range(14):
        obs, _, _, _, info = env.step(pose)
        np.testing.assert_allclose(info["command"], np.tile(command.values, (3, 1)))
        np.testing.assert_allclose(obs[:, 6:9], np.tile(command.values, (3, 1)), rtol=1e-6)
    env.close()


@pytest.mark.parametrize("robot_name, recipe", [("go1", "PLAYGROUND"), ("anymal", "LEGGED_GYM")])
def test_a_grid_command_is_held_under_the_field_recipes(robot_name, recipe):
    """The recipes' own command processes (Playground's exponential times, zeroed and kept
    entries; legged_gym's heading command and small commands zeroed) are off in a grid row:
    its command, a yaw rate and a slow lateral one among them, is held from reset to the end."""
    robot = get_robot(robot_name)
    values = {k: v for k, v in getattr(robot.config_class, recipe).items() if k != "randomize"}
    config = robot.config_class.from_dict({**values, "episode_seconds": 0.3})
    for command in (protocol.GRID[10], protocol.GridCommand("slow", 0.0, 0.15, 0.8)):
        env = robot.make(3, protocol.command_env(config, command), num_threads=1)
        _, info = env.reset(seed=3)
        pose = np.tile(np.asarray(env.quadruped.nominal_pose), (3, 1))
        for _ in range(14):
            np.testing.assert_allclose(info["command"], np.tile(command.values, (3, 1)))
            _, _, _, _, info = env.step(pose)
        env.close()


def test_the_grid_and_its_checks():
    """Every direction, both signs, standing; within the field's ranges; the checks sized by
    the moving mass (the Go1's 12.74 kg: 14.65 kg of payload, 12.74 N s pushes), the push
    inside a short episode."""
    values = np.array([c.values for c in protocol.GRID])
    assert (values[:, 0].min(), values[:, 0].max()) == (-1.0, 1.0)
    assert values[:, 1].min() < 0 < values[:, 1].max() and np.abs(values[:, 1]).max() <= 0.5
    assert (values[:, 2].min(), values[:, 2].max()) == (-1.0, 1.0)
    assert [0.0, 0.0, 0.0] in values.tolist()
    # the cost of transport only where the command travels: not turning on the spot, standing
    assert [c.name for c in protocol.GRID if not c.moves] == [
        "turn left 0.5",
        "turn left 1.0",
        "turn right 0.5",
        "turn right 1.0",
        "standing",
    ]
    mass = get_robot("go1").config_class.moving_mass
    checks = dict(protocol.checks(mass, 0.2))
    assert checks["payload 115%"]["payload"] == pytest.approx(1.15 * mass, abs=0.01)
    for side in ("left", "right"):
        push = checks[f"push {side} 1 m/s"]
        assert push["push"] == pytest.approx(mass, abs=0.01) and push["push_direction"] == side
        assert push["push_time"][1] < 0.2
    assert dict(protocol.checks(mass, 20.0))["push left 1 m/s"]["push_time"] == (1.0, 2.0)


@pytest.fixture(scope="module")
def go1_run(tmp_path_factory):
    """A tiny trained Go1 run of the omnidirectional task."""
    from tiny import trained_run

    omni = {k: list(v) if isinstance(v, tuple) else v
            for k, v in get_robot("go1").config_class.OMNI_COMMANDS.items()}  # fmt: skip
    return trained_run(tmp_path_factory.mktemp("go1") / "run", "cpg-actor", "go1",
                       env={"episode_seconds": 0.2, **omni})  # fmt: skip


def test_the_grid_runs_on_a_trained_go1_and_writes_its_table(go1_run, capsys):
    code = main(["eval", str(go1_run), "--grid", "--episodes", "1",
                 "--set", "env.episode_seconds=0.2"])  # fmt: skip
    assert code == 0
    out = capsys.readouterr().out
    assert "mean over the grid" in out and "push left 1 m/s" in out and "lin vel err" in out
    assert "*" not in out.split("terrain", 1)[1]  # every command within the omni ranges
    result = json.loads((go1_run / "eval" / "grid.json").read_text())
    rows = result["rows"]
    names = [row["check"] or row["command"] for row in rows]
    assert names == [c.name for c in protocol.GRID] + ["payload 115%", "push left 1 m/s",
                                                       "push right 1 m/s"]  # fmt: skip
    for row in rows:
        assert row["terrain"] == "flat"
        for key in ("lin_vel_error", "yaw_rate_error", "fell", "torque_rate", "foot_slip",
                    "duty_factor"):  # fmt: skip
            assert row[key] is not None and row[key] >= 0
    # the turning rows: an untrained policy barely turns, its yaw-rate error near the command
    turn = next(row for row in rows if row["command"] == "turn left 1.0")
    assert turn["yaw_rate_error"] > 0.5
    assert set(result["means"]["flat"]) == {key for key, _ in protocol.COLUMNS}
    table = list(csv.DictReader((go1_run / "eval" / "grid.csv").open()))
    assert len(table) == len(rows) + 1 and table[-1]["command"] == "mean"
    assert float(table[0]["lin_vel_error"]) == pytest.approx(rows[0]["lin_vel_error"])


def test_the_grid_runs_on_flat_ground_and_at_a_terrain_level(go1_run, tmp_path):
    """--grid-levels: the grid and its checks on flat ground, then on every kind of tile at
    the level asked for (the curriculum off), each row naming its ground."""
    output = tmp_path / "levels" / "traces.npz"
    code = main(["eval", str(go1_run), "--grid", "--grid-levels", "3", "--episodes", "1",
                 "--output", str(output)])  # fmt: skip
    assert code == 0
    result = json.loads((output.parent / "grid.json").read_text())
    grounds = [row["terrain"] for row in result["rows"]]
    rows = len(protocol.GRID) + 3
    assert grounds == ["flat"] * rows + ["all level 3"] * rows
    assert list(result["means"]) == ["flat", "all level 3"]
    config = get_robot("go1").config_class()
    ground = protocol.terrain_level(config, 3)
    assert protocol.ground_name(config.replace(**ground)) == "all level 3"
    assert protocol.ground_name(config.replace(**protocol.flat_ground(config))) == "flat"


def test_a_forward_only_run_gets_its_untrained_rows_marked(tmp_path, capsys):
    from tiny import trained_run

    run = trained_run(tmp_path / "run", "mlp", "go1", env={"episode_seconds": 0.2})
    assert protocol.untrained_commands(get_robot("go1").config_class()) == [
        c.name for c in protocol.GRID if c.values[0] < 0 or c.values[1:] != (0.0, 0.0)
    ]
    out_dir = tmp_path / "mine"
    out_dir.mkdir()
    (out_dir / "grid.csv").write_text("mine\n")
    args = ["eval", str(run), "--grid", "--episodes", "1", "--output",
            str(out_dir / "traces.npz")]  # fmt: skip
    assert main(args) == 2  # the user's file is kept
    assert "exists; pass --overwrite" in capsys.readouterr().err
    assert (out_dir / "grid.csv").read_text() == "mine\n"
    assert main([*args, "--overwrite"]) == 0
    out = capsys.readouterr().out
    assert "trained without" in out and "turn left 1.0 *" in out
    assert (out_dir / "grid.csv").read_text().startswith("terrain,command")


def test_bad_input_is_one_clear_line(tmp_path, capsys, go1_run):
    from tiny import trained_run

    hopper = trained_run(tmp_path / "hopper", "cpg-actor")
    assert main(["eval", str(hopper), "--grid"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "quadruped" in err and "hopper" in err
    for args in (["--grid", "--grid-levels", "10"], ["--grid-levels", "2"]):
        assert main(["eval", str(go1_run), *args]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and ("0..9" in err or "needs --grid" in err)
    assert main(["eval", str(go1_run), "--grid", "--video", str(tmp_path / "v.mp4")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--grid" in err
    assert not (tmp_path / "v.mp4").exists()


def test_a_state_saved_before_the_new_metrics_still_resumes():
    """A checkpoint's env state from before the tracking metrics lacks their sums: it resumes
    with them at zero, and the episode's metrics come out finite."""
    robot = get_robot("go1")
    env = robot.make(2, robot.config_class(episode_seconds=0.1), num_threads=1)
    env.reset(seed=0)
    pose = np.tile(np.asarray(env.quadruped.nominal_pose), (2, 1))
    env.step(pose)
    state = env.get_state()
    fields = state[env.quadruped.state_key]
    for name in ("lin_vel_error_sum", "yaw_rate_error_sum", "contact_steps", "path_length",
                 "velocity_offset_sum"):  # fmt: skip
        del fields[name]
    env.set_state(state)
    for _ in range(4):
        *_, info = env.step(pose)
    for name in ("lin_vel_error", "yaw_rate_error", "duty_factor"):
        assert np.isfinite(info["episode_metrics"][name]).all()
    env.close()
