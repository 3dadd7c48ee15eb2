"""The physical metrics (cpg_actor.metrics.physical) on hand-made traces with known
answers, on old traces without their data, and from `cpg-actor eval` on a tiny run."""

import math

import numpy as np
import pytest

from cpg_actor.metrics import physical as p


def hops(apexes, flight=11, stance=5, standing=0.3, start_stance=5):
    """Hip heights and contacts (T,) of flights peaking ``standing + apex`` (a triangle per
    flight of an odd number of steps), each between stance phases at ``standing``."""
    height, contact = [standing] * start_stance, [True] * start_stance
    for apex in apexes:
        height += list(standing + apex * (1 - np.abs(np.linspace(-1, 1, flight))))
        contact += [False] * flight
        height += [standing] * stance
        contact += [True] * stance
    return np.asarray(height, dtype=float), np.asarray(contact)


def test_two_flights_have_their_apexes_and_the_hop_apex_is_their_median():
    height, contact = hops([0.5, 0.6], standing=0.3)
    assert len(p.flights(contact)) == 2
    assert p.flight_apexes(height, contact, standing=0.3) == pytest.approx([0.5, 0.6])
    assert p.hop_apex(height, contact, standing=0.3) == pytest.approx(0.55)


def test_a_push_at_the_start_raises_the_highest_hip_but_not_the_hop_apex():
    height, contact = hops([1.2, 0.5, 0.6, 0.5], standing=0.3)
    pushed = np.zeros(len(height), dtype=bool)
    pushed[4] = True  # the step before the first lift-off: that flight is the push's
    assert height.max() - 0.3 == pytest.approx(1.2)  # the env's hop height: the push's
    assert p.flight_apexes(height, contact, 0.3, pushed) == pytest.approx([0.5, 0.6, 0.5])
    assert p.hop_apex(height, contact, 0.3, pushed) == pytest.approx(0.5)
    # unmarked, one high flight among several cannot move the median far
    assert p.hop_apex(height, contact, 0.3) == pytest.approx(0.55)


def test_no_whole_flight_is_a_hop_apex_of_zero_and_open_flights_do_not_count():
    standing = np.full(20, 0.3)
    assert p.hop_apex(standing, np.ones(20, dtype=bool), 0.3) == 0.0
    contact = np.array([False] * 5 + [True] * 10 + [False] * 5)  # starts and ends in the air
    assert p.flights(contact) == []
    assert p.hop_apex(np.linspace(1.0, 0.0, 20), contact) == 0.0


def test_the_flights_of_the_start_up_are_left_out_with_settle():
    height, contact = hops([0.1, 0.5, 0.6], stance=20, start_stance=5)
    assert p.hop_apex(height, contact, 0.3) == pytest.approx(0.5)
    assert p.hop_apex(height, contact, 0.3, settle=10) == pytest.approx(0.55)


def test_joint_smoothness_of_a_sine_is_its_squared_second_difference():
    amplitude, period, steps = 0.4, 50, 1000
    t = np.arange(steps)
    q = amplitude * np.sin(2 * np.pi * t / period)[:, None] * np.array([1.0, 0.5])
    expected = 0.5 * amplitude**2 * (2 * np.pi / period) ** 4 * (1 + 0.25) / 2
    assert p.joint_smoothness(q) == pytest.approx(expected, rel=0.01)
    exact = (q[2:] - 2 * q[1:-1] + q[:-2]) ** 2
    assert p.joint_smoothness(q) == pytest.approx(exact.mean(), rel=1e-12)
    assert p.joint_smoothness(np.outer(t, [0.01, -0.02])) == pytest.approx(0.0, abs=1e-20)


def test_torque_rate_power_slip_and_the_joint_stop():
    dt = 0.01
    torque = np.outer(np.arange(10), [0.5, -2.0])  # N m, ramps of 0.5 and 2 N m per step
    assert p.torque_rate(torque, dt) == pytest.approx((50.0 + 200.0) / 2)
    velocity = np.tile([3.0, 1.0], (10, 1))
    power = np.abs(torque * velocity).sum(axis=1).mean()
    assert p.mechanical_power(torque, velocity) == pytest.approx(power)
    assert p.mechanical_power(np.full((4, 2), 2.0), np.array([[3.0, -3.0]] * 4)) == 12.0
    # one foot sliding at 0.1 m/s while on the ground, then flying at 2 m/s (not slip)
    x = np.concatenate([0.001 * np.arange(6), 0.005 + 0.02 * np.arange(1, 5)])
    feet = np.stack([x, np.zeros_like(x), np.zeros_like(x)], axis=-1)[:, None, :]
    contact = np.array([True] * 6 + [False] * 4)[:, None]
    assert p.foot_slip(feet, contact, dt) == pytest.approx(0.1)
    assert math.isnan(p.foot_slip(feet, np.zeros_like(contact), dt))
    joints = np.array([[0.0, 0.0], [0.995, 0.0], [0.5, -0.999], [0.5, 0.2]])
    assert p.joint_stop_share(joints, [-1.0, -1.0], [1.0, 1.0]) == pytest.approx(0.5)
    with pytest.raises(ValueError, match="dt must be > 0"):
        p.torque_rate(torque, 0.0)


def traces_of(height, contact, episodes=2, tail=3):
    """An evaluation's traces (T, E, ...) of the hopper from one episode's hip and contacts,
    the second episode ``tail`` steps shorter (NaN rows after it ended)."""
    steps = len(height)
    length = np.array([steps] + [steps - tail] * (episodes - 1))

    def rows(x):
        out = np.repeat(np.asarray(x, dtype=float)[:, None], episodes, axis=1)
        for e in range(1, episodes):
            out[steps - tail :, e] = np.nan
        return out

    joints = np.stack([np.sin(0.1 * np.arange(steps)), np.cos(0.1 * np.arange(steps))], -1)
    torque = np.stack([rows(joints[:, 0] * 10), rows(joints[:, 1] * 10)], -1)
    return {
        "length": length,
        "control_dt": np.array(0.01),
        "hip_height": rows(height),
        "foot_height": rows(np.where(contact, 0.0, 0.05)),
        "standing_hip_height": np.array(0.3),
        "measured_position": np.stack([rows(joints[:, 0]), rows(joints[:, 1])], -1),
        "desired_position": np.stack([rows(joints[:, 0]), rows(joints[:, 1])], -1),
        "action_low": np.array([-0.5, -1.7]),
        "action_high": np.array([1.3, 0.1]),
        "joint_torque": torque,
        "joint_velocity": np.stack(
            [rows(np.cos(0.1 * np.arange(steps))), rows(-np.sin(0.1 * np.arange(steps)))], -1
        ),  # fmt: skip
    }


def test_per_episode_metrics_of_traces_and_old_traces_without_their_data():
    # a start-up hop of 0.1 m in the first second (left out), then three flights
    height, contact = hops([0.1, 0.5, 0.6, 0.7], stance=100, standing=0.3)
    traces = traces_of(height, contact)
    values = p.episode_metrics(traces)
    assert list(values) == [name for name in p.METRICS if name != "foot_slip"]
    assert values["hop_apex"] == pytest.approx([0.6, 0.6])  # the last stance cut: 3 flights
    assert np.isfinite(values["torque_rate"]).all()
    assert values["joint_smoothness"] == pytest.approx(values["command_smoothness"])
    # traces saved before the torques, velocities and feet: those metrics are absent
    old = {k: v for k, v in traces.items() if k not in ("joint_torque", "joint_velocity")}
    old_values = p.run_metrics(old)
    assert math.isnan(old_values["torque_rate"]) and math.isnan(old_values["mechanical_power"])
    assert old_values["hop_apex"] == pytest.approx(0.6)
    assert all(math.isnan(v) for v in p.run_metrics(None).values())


def test_eval_of_a_tiny_run_prints_and_saves_the_physical_metrics(tmp_path, capsys):
    from cpg_actor.cli import main
    from tiny import trained_run  # tests/tiny.py

    run = trained_run(tmp_path / "run", "cpg-actor")
    assert main(["eval", str(run), "--episodes", "2", "--set", "env.episode_steps=60"]) == 0
    printed = capsys.readouterr().out
    assert "physical (mean over episodes): hop apex" in printed and "torque rate" in printed
    traces = dict(np.load(run / "eval" / "traces.npz"))
    names = [str(name) for name in traces["physical_names"]]
    assert names == list(p.METRICS)  # the hopper has every one
    for name in names:
        assert traces[f"physical_{name}"].shape == (2,)
    assert traces["foot_position"].shape[-2:] == (1, 3)
    assert traces["joint_torque"].shape[-1] == 2
    assert traces["physical_torque_rate"] == pytest.approx(
        [p.torque_rate(traces["joint_torque"][:, e], 0.01) for e in range(2)])  # fmt: skip
    assert np.all(traces["physical_hop_apex"] <= traces["hop_height"] + 1e-9)
