"""The figures and printed lines of `cpg-actor eval`, from constructed traces and metrics rows
(no training): they follow the robot (its metrics, its joints and legs), are titled, label
their axes in plain words with units, mark the motor's speed limit on joint velocities and
keep legends off the data."""

from __future__ import annotations

import numpy as np
import pytest

from cpg_actor.commands.eval import episode_lines, traces_figure, training_curves_figure
from cpg_actor.plots import metric_label, step_labels
from cpg_actor.robots.registry import all_metrics

QUADRUPED_METRICS = ("cost_of_transport", "episode_seconds", "fell", "foot_slip",
                     "forward_speed", "speed_error")  # fmt: skip
LEGS = ("LF", "RF", "LH", "RH")


def _texts(fig) -> str:
    """Every title, axis label and legend entry of a figure, one string."""
    parts = [fig._suptitle.get_text() if fig._suptitle else ""]
    for axis in fig.axes:
        parts += [axis.get_title(), axis.get_xlabel(), axis.get_ylabel()]
        legend = axis.get_legend()
        if legend is not None:
            parts += [text.get_text() for text in legend.get_texts()]
        parts += [text.get_text() for text in axis.texts]
    for legend in fig.legends:
        parts += [text.get_text() for text in legend.get_texts()]
    return "\n".join(parts)


def _rows(metrics: tuple[str, ...], steps=(0, 2048, 4096)) -> list[dict]:
    """metrics.jsonl rows of a run whose training episodes never finished (charts/ None) and
    whose deterministic evaluations logged the env's metrics."""
    rows = []
    for i, step in enumerate(steps):
        row = {"iteration": i, "global_step": step, "charts/episode_return": None,
               "eval/return": 10.0 + i, "eval/return_min": 5.0, "eval/length": 1000.0}  # fmt: skip
        row.update({f"eval/{name}": 0.1 * (i + 1) for name in metrics})
        rows.append(row)
    return rows


def _panels(fig) -> dict[str, object]:
    """The visible panels of a figure by their title."""
    return {axis.get_title(): axis for axis in fig.axes if axis.get_visible()}


def test_the_quadrupeds_training_curves_show_its_own_metrics_and_no_hop_height():
    fig = training_curves_figure(_rows(QUADRUPED_METRICS), QUADRUPED_METRICS, "run: anymal")
    panels = _panels(fig)
    assert "hop height" not in _texts(fig)
    assert set(panels) == {"episode return", *map(metric_label, QUADRUPED_METRICS)}
    assert "forward-speed error (m/s)" in panels and "forward speed (m/s)" in panels
    # the task's metrics first, after the return
    order = [axis.get_title() for axis in fig.axes if axis.get_visible()]
    assert order[:3] == ["episode return", "forward-speed error (m/s)", "forward speed (m/s)"]
    for title, axis in panels.items():  # every panel draws the evaluations it logged
        assert [len(line.get_xdata()) for line in axis.get_lines()] == [3], title
        assert axis.get_xlabel()
    assert "run: anymal" in fig._suptitle.get_text()
    # one legend under the panels, none inside one (no data covered)
    assert len(fig.legends) == 1 and all(a.get_legend() is None for a in fig.axes)
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["deterministic evaluation"]


def test_the_hoppers_training_curves_show_the_hop_height_from_training_and_evaluation():
    rows = _rows(("hop_height",))
    rows[1]["charts/episode_return"], rows[1]["charts/hop_height"] = 300.0, 0.3
    rows[2]["charts/episode_return"], rows[2]["charts/hop_height"] = 400.0, 0.4
    fig = training_curves_figure(rows, ("hop_height",), "hop")
    panels = _panels(fig)
    assert set(panels) == {"episode return", "hop height (m)"}
    lines = {line.get_label(): line for line in panels["hop height (m)"].get_lines()}
    assert list(lines["training episodes (exploring)"].get_xdata()) == [2048, 4096]
    assert list(lines["deterministic evaluation"].get_ydata()) == pytest.approx([0.1, 0.2, 0.3])
    # without metric names: the env's metrics as the evaluations logged them
    assert set(_panels(training_curves_figure(rows, (), "hop"))) == set(panels)


def test_a_run_that_logged_nothing_yet_says_so():
    rows = [{"iteration": 0, "global_step": 0, "charts/episode_return": None}]
    assert "no finished episode and no evaluation" in _texts(training_curves_figure(rows))


def _hopper_traces(steps: int = 500, limit: float = 12.0) -> dict[str, np.ndarray]:
    t = 0.01 * np.arange(1, steps + 1)
    wave = np.sin(2 * np.pi * 1.2 * t)[:, None, None]
    position = np.concatenate([0.4 + 0.3 * wave, -0.8 + 0.6 * wave], axis=-1)
    velocity = np.gradient(position, 0.01, axis=0)
    return {
        "time": t,
        "length": np.array([steps]),
        "control_dt": np.array(0.01),
        "joint_names": np.array(["HFE", "KFE"]),
        "desired_position": position,
        "measured_position": position - 0.05,
        "desired_velocity": velocity,
        "measured_velocity": 1.5 * velocity,
        "theta_dot": np.full((steps, 1, 2), 7.5),
        "r_ddot": np.zeros((steps, 1, 2)),
        "hip_height": 0.5 + 0.2 * np.abs(wave[:, :, 0]),
        "foot_height": 0.1 * np.abs(wave[:, :, 0]),
        "velocity_limit": np.array(limit),
    }


def _limit_lines(axis) -> list[float]:
    """The y of the horizontal dashed lines on an axis."""
    return sorted(
        float(line.get_ydata()[0])
        for line in axis.get_lines()
        if line.get_linestyle() == "--" and len(set(line.get_ydata())) == 1
    )


def test_the_hoppers_traces_are_titled_in_plain_words_with_the_motor_speed_limit():
    fig = traces_figure(_hopper_traces(limit=12.0), "hop: cpg-actor on the hopper")
    text = _texts(fig)
    assert fig._suptitle.get_text() == (
        "hop: cpg-actor on the hopper: evaluation episode 0, whole episode (5 s)"
    )
    labels = [axis.get_ylabel() for axis in fig.axes]
    assert labels[:2] == ["joint position (rad)", "joint velocity (rad/s)"]
    assert "phase" in labels[2] and "(rad/s)" in labels[2]
    assert "amplitude" in labels[3] and "(rad/s$^2$)" in labels[3]
    assert labels[4] == "height (m)"
    assert "theta_dot" not in text and "r_ddot" not in text
    # +- the limit the traces carry (the run's env config), on the velocity panel only
    assert _limit_lines(fig.axes[1]) == [-12.0, 12.0]
    assert "motor speed limit ±12 rad/s" in text
    assert _limit_lines(fig.axes[0]) == [] and _limit_lines(fig.axes[2]) == []
    for axis in fig.axes:  # legends outside the axes, to their right
        legend = axis.get_legend()
        assert legend is not None and legend.get_bbox_to_anchor().x0 > axis.bbox.x1


def _quadruped_traces(seconds: float = 20.0) -> dict[str, np.ndarray]:
    steps = round(seconds / 0.02)
    t = 0.02 * np.arange(1, steps + 1)
    joints = [f"{leg}_{joint}" for leg in LEGS for joint in ("HAA", "HFE", "KFE")]
    wave = np.sin(2 * np.pi * 3 * t)[:, None, None] * np.linspace(0.1, 1.2, 12)
    return {
        "time": t,
        "length": np.array([steps, steps]),
        "control_dt": np.array(0.02),
        "joint_names": np.array(joints),
        "desired_position": np.repeat(wave, 2, axis=1),
        "measured_position": np.repeat(wave, 2, axis=1) * 0.9,
        "desired_velocity": np.repeat(np.gradient(wave, 0.02, axis=0), 2, axis=1),
        "theta_dot": np.full((steps, 2, 4), 18.8),
        "r_ddot": np.zeros((steps, 2, 4)),
        "oscillator_names": np.array(LEGS),
        "velocity_limit": np.array(15.0),
    }


def test_the_quadrupeds_traces_show_every_leg_over_its_last_seconds():
    fig = traces_figure(_quadruped_traces(), "quad")
    assert "last 2 s of 20 s" in fig._suptitle.get_text()
    axes = np.array(fig.axes).reshape(4, 4)  # rows: position, velocity, theta_dot, r_ddot
    assert [axis.get_title() for axis in axes[0]] == list(LEGS)
    for column in range(len(LEGS)):
        position = axes[0, column]
        desired = [line for line in position.get_lines() if line.get_linestyle() == "-"]
        assert [line.get_label() for line in desired] == ["HAA", "HFE", "KFE"]
        time = desired[0].get_xdata()
        assert time[0] == pytest.approx(18.02) and time[-1] == pytest.approx(20.0)
        # that leg's joints: its HFE is joint 3 column + 1 of the desired positions
        wave = _quadruped_traces()["desired_position"][-100:, 0, 3 * column + 1]
        assert desired[1].get_ydata() == pytest.approx(wave)
        assert _limit_lines(axes[1, column]) == [-15.0, 15.0]
        assert [line.get_label() for line in axes[2, column].get_lines()] == ["leg oscillator"]
    assert "hop" not in _texts(fig) and "height" not in _texts(fig)


def test_an_undefined_metric_prints_as_a_dash_with_a_footnote_and_the_mean_says_over_what():
    traces = {
        "metric_names": np.array(["cost_of_transport", "forward_speed"]),
        "episode_return": np.array([10.0, 12.0, 14.0]),
        "length": np.array([1000, 1000, 1000]),
        "cost_of_transport": np.array([2.0, np.nan, 4.0]),
        "forward_speed": np.array([0.3, 0.01, 0.5]),
    }
    lines = episode_lines(traces)
    assert "nan" not in "\n".join(lines).lower()
    assert lines[1] == (
        "episode 1: return 12.000, cost_of_transport —, forward_speed 0.010, 1000 steps"
    )
    assert lines[3] == (
        "mean return 12.000, mean cost_of_transport 3.000 (over the 2 of 3 episodes that "
        "define it), mean forward_speed 0.270 over 3 episodes"
    )
    assert lines[4].startswith("—: cost_of_transport is undefined for an episode where ")
    assert all_metrics()["cost_of_transport"].undefined in lines[4]
    assert len(lines) == 5  # forward_speed is defined for every episode: no footnote
    # every episode defined: no footnote, no count
    traces["cost_of_transport"] = np.array([2.0, 3.0, 4.0])
    assert episode_lines(traces)[-1] == (
        "mean return 12.000, mean cost_of_transport 3.000, mean forward_speed 0.270 over 3 episodes"
    )


@pytest.mark.parametrize(
    ("steps", "labels"),
    [
        ([0, 0, 4096], ["0", "0", "4.1k"]),
        ([0, 68_267, 4096], ["0", "68.3k", "4.1k"]),
        ([333_333, 6_666_667, 20_000_000], ["0.333M", "6.67M", "20M"]),
        ([1_000_000, 1_000_500, 2_000_000], ["1M", "1.0005M", "2M"]),
        ([10, 20], ["10", "20"]),
    ],
)
def test_step_labels_pick_k_or_m_by_the_budget_and_tell_different_counts_apart(steps, labels):
    assert step_labels(steps) == labels
