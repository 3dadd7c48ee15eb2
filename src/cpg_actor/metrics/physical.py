"""Physical metrics of an evaluation: what the robot did, measured on its hip, joints and feet,
by the same code for every agent and robot.

Why: the headline numbers can pass for the wrong reason. The hop height an env reports is an
episode's highest hip height, which an upward push or a slippery floor raises; the smoothness
of the command is smooth by construction for a CPG, whatever the joints do. These metrics read
the evaluation's traces (:func:`cpg_actor.training.evaluation.evaluate`) instead:

* **hop apex** (m, the hopper's): the highest hip height of each flight phase (no foot on the
  ground, between a lift-off and a touchdown seen in the episode) above the standing hip
  height, the median over the episode's flights (:func:`flight_apexes`, :func:`hop_apex`)
  that lift off after the start-up (:data:`SETTLE_SECONDS`: the first hops from standing
  are lower). A flight in which a perturbation's push came is left out, and one odd flight
  cannot move a median; 0 for an episode with contacts but no such flight (it never left
  the ground);
* **joint smoothness** (rad^2 per control step^2): the mean squared second difference of the
  measured joint positions, ``(q[t+1] - 2 q[t] + q[t-1])^2`` (:func:`joint_smoothness`);
* **command smoothness** (rad^2): the same of the desired positions sent (the report's
  ``smoothness``), kept as its own column;
* **torque rate** (N m/s): the mean over steps and joints of ``|tau[t] - tau[t-1]| / dt``
  (:func:`torque_rate`);
* **mechanical power** (W): the mean over steps of ``sum_j |tau_j qdot_j|``, the motors'
  absolute power (:func:`mechanical_power`);
* **foot slip** (m/s): the horizontal speed of a foot on the ground at both ends of a control
  step, ``|xy[t] - xy[t-1]| / dt``, averaged over every such foot and step
  (:func:`foot_slip`; the quadruped task's ``planted_slip``, as its episode metric);
* **time at a joint stop** (share of steps): the share of control steps at which a measured
  joint position lies within :data:`JOINT_STOP_MARGIN` of its joint's limit or beyond
  (:func:`joint_stop_share`).

The functions take one episode's rows ``(T, ...)``; :func:`episode_metrics` applies each one
a trace file has the data for to each of its episodes, :func:`run_metrics` averages them over
the episodes (the report's per-seed number). A metric whose data a trace file lacks (traces
saved before these metrics, a robot without a hip) is absent, never 0.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cpg_actor.metrics.signals import joint_stop_share as _stop_share
from cpg_actor.metrics.signals import smoothness

# m: a foot whose lowest point is this close to the ground touches it (the hopper's foot
# height; the quadrupeds trace their contacts, with the same 5 mm margin)
CONTACT_HEIGHT = 0.005
# rad: a measured joint position this close to its limit sits at the stop (a joint pressed
# into its limit penetrates it by a few mrad in MuJoCo)
JOINT_STOP_MARGIN = 0.01
# s: the hop apex leaves out the flights that lift off this early (the start-up from
# standing, whose first hops are lower: the packaged start gait's are 0.02, 0.13 and 0.38 m
# before it settles near 0.5 m)
SETTLE_SECONDS = 1.0


@dataclass(frozen=True)
class PhysicalMetric:
    label: str  # in words, for a column
    unit: str

    @property
    def column(self) -> str:
        return f"{self.label} ({self.unit})" if self.unit else self.label


# in the order eval and the reports show them
METRICS = {
    "hop_apex": PhysicalMetric("hop apex", "m"),
    "joint_smoothness": PhysicalMetric("joint smoothness", "rad^2"),
    "command_smoothness": PhysicalMetric("command smoothness", "rad^2"),
    "torque_rate": PhysicalMetric("torque rate", "N m/s"),
    "mechanical_power": PhysicalMetric("mechanical power", "W"),
    "foot_slip": PhysicalMetric("foot slip", "m/s"),
    "time_at_joint_stop": PhysicalMetric("time at a joint stop", ""),
}


def flights(contact: np.ndarray) -> list[tuple[int, int]]:
    """The flight phases of an episode from its contacts (``(T,)`` bool, True: a foot on the
    ground): ``(start, end)`` row ranges of the steps with no foot on the ground, each after a
    step on the ground and before one (a lift-off and a touchdown seen in the episode; the
    start and end of the episode in the air are no whole flight)."""
    air = ~np.asarray(contact, dtype=bool)
    edges = np.diff(air.astype(np.int8))
    starts = np.flatnonzero(edges == 1) + 1  # lift-off: on the ground, then in the air
    ends = np.flatnonzero(edges == -1) + 1  # touchdown: the first step on the ground again
    return [(int(a), int(ends[ends > a][0])) for a in starts if (ends > a).any()]


def flight_apexes(height: np.ndarray, contact: np.ndarray, standing: float = 0.0,
                  pushed: np.ndarray | None = None, settle: int = 0) -> np.ndarray:  # fmt: skip
    """Each flight's apex (m): the highest ``height`` (``(T,)``, the hip's) of its steps
    above ``standing``. ``pushed`` (``(T,)``, True at a push's step): a flight in which a push
    came (from the step before its lift-off to its touchdown) is left out; so is one that
    lifts off before step ``settle``."""
    height = np.asarray(height, dtype=float)
    push_steps = np.flatnonzero(np.asarray(pushed, dtype=bool)) if pushed is not None else []
    apexes = []
    for start, end in flights(contact):
        if start < settle or any(start - 1 <= step <= end for step in push_steps):
            continue
        apexes.append(np.nanmax(height[start:end]) - standing)
    return np.asarray(apexes, dtype=float)


def hop_apex(height: np.ndarray, contact: np.ndarray, standing: float = 0.0,
             pushed: np.ndarray | None = None, settle: int = 0) -> float:  # fmt: skip
    """An episode's hop apex (m): the median of its :func:`flight_apexes`; 0 for an episode
    without such a flight (it never left the ground, or only when pushed or starting)."""
    apexes = flight_apexes(height, contact, standing, pushed, settle)
    return float(np.median(apexes)) if apexes.size else 0.0


def joint_smoothness(joint_position: np.ndarray) -> float:
    """Mean over steps and joints of the squared second difference of the measured joint
    positions ``(T, J)``, ``(q[t+1] - 2 q[t] + q[t-1])^2`` (rad^2 per control step^2): 0 for
    joints moving at constant speed, about ``A^2 (2 pi / n)^4 / 2`` for a sine of amplitude A
    and period n steps."""
    return smoothness(joint_position)


def torque_rate(torque: np.ndarray, dt: float) -> float:
    """Mean over steps and joints of ``|tau[t] - tau[t-1]| / dt`` (N m/s) from the joint
    torques ``(T, J)`` (N m) and the control period ``dt`` (s); NaN under two steps."""
    tau = np.asarray(torque, dtype=float)
    if not dt > 0:
        raise ValueError(f"the control period dt must be > 0, got {dt!r}")
    rate = np.abs(np.diff(tau, axis=0)) / dt
    rate = rate[np.isfinite(rate)]
    return float(rate.mean()) if rate.size else float("nan")


def mechanical_power(torque: np.ndarray, joint_velocity: np.ndarray) -> float:
    """Mean over steps of the motors' absolute mechanical power ``sum_j |tau_j qdot_j|`` (W),
    from the joint torques (N m) and velocities (rad/s), both ``(T, J)``; steps with a missing
    value left out."""
    power = np.abs(np.asarray(torque, dtype=float) * np.asarray(joint_velocity, dtype=float))
    steps = power.reshape(len(power), -1)
    steps = steps[np.isfinite(steps).all(axis=1)]
    return float(steps.sum(axis=1).mean()) if steps.size else float("nan")


def foot_slip(foot_position: np.ndarray, contact: np.ndarray, dt: float) -> float:
    """The mean horizontal speed (m/s) of the feet planted over a control step: a foot is
    planted from step t-1 to t when it touches the ground at both; its slip is then
    ``|xy[t] - xy[t-1]| / dt``. ``foot_position`` ``(T, feet, 3)`` (m, world), ``contact``
    ``(T, feet)`` bool. NaN when no foot was ever planted."""
    xy = np.asarray(foot_position, dtype=float)[..., :2]
    touching = np.asarray(contact, dtype=bool)
    if not dt > 0:
        raise ValueError(f"the control period dt must be > 0, got {dt!r}")
    planted = touching[1:] & touching[:-1]
    speed = np.linalg.norm(xy[1:] - xy[:-1], axis=-1) / dt
    planted &= np.isfinite(speed)
    return float(speed[planted].mean()) if planted.any() else float("nan")


def joint_stop_share(joint_position: np.ndarray, low: Sequence[float], high: Sequence[float],
                     margin: float = JOINT_STOP_MARGIN) -> float:  # fmt: skip
    """The share of control steps (rows of ``(T, J)`` measured positions) at which a joint
    lies within ``margin`` (rad) of its limit ``low[j]`` or ``high[j]``, or beyond it."""
    return _stop_share(joint_position, low, high, tolerance=margin)


# the traces the metrics read, (T, E, ...) each
TRACED = ("hip_height", "foot_height", "foot_contact", "foot_position", "joint_position",
          "measured_position", "joint_velocity", "measured_velocity", "joint_torque",
          "desired_position", "push")  # fmt: skip


def _first(traces, *keys):
    return next((np.asarray(traces[key], dtype=float) for key in keys if key in traces), None)


def episode_metrics(traces: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Per episode (``(E,)`` each), every metric of :data:`METRICS` whose data ``traces``
    (an evaluation's, ``(T, E, ...)`` rows, NaN after an episode ended) holds: the joints'
    true positions and velocities (``joint_position``, ``joint_velocity``; traces saved
    before them: the observed ``measured_position``, ``measured_velocity``), the torques,
    the feet's positions and contacts (``foot_contact``; the hopper's from ``foot_height``),
    the hip's height."""
    if "length" in traces:
        lengths = np.asarray(traces["length"], dtype=int)
    else:  # traces without episode lengths: every row (the metrics leave NaN rows out)
        shaped = [np.shape(traces[key]) for key in TRACED if key in traces]
        shaped = [shape for shape in shaped if len(shape) >= 2]
        if not shaped:
            return {}
        lengths = np.full(shaped[0][1], shaped[0][0], dtype=int)
    episodes = len(lengths)
    dt = None  # the control period: saved, else the traces' time step
    if "control_dt" in traces:
        dt = float(traces["control_dt"])
    elif "time" in traces and np.size(traces["time"]) > 1:
        dt = float(traces["time"][1] - traces["time"][0])
    position = _first(traces, "joint_position", "measured_position")
    velocity = _first(traces, "joint_velocity", "measured_velocity")
    torque = _first(traces, "joint_torque")
    desired = _first(traces, "desired_position")
    if "foot_contact" in traces:
        contact = np.nan_to_num(np.asarray(traces["foot_contact"], dtype=float)) > 0.5
    elif "foot_height" in traces and np.isfinite(np.asarray(traces["foot_height"],
                                                            dtype=float)).any():  # fmt: skip
        contact = (np.asarray(traces["foot_height"], dtype=float) < CONTACT_HEIGHT)[..., None]
    else:
        contact = None
    limits = None
    if position is not None and "action_low" in traces and "action_high" in traces:
        low, high = (np.atleast_1d(np.asarray(traces[k], dtype=float))
                     for k in ("action_low", "action_high"))  # fmt: skip
        if low.size == position.shape[-1]:
            limits = (low, high)
    hip = _first(traces, "hip_height")
    standing = float(traces.get("standing_hip_height", np.nan))  # none: no apex above it
    push = _first(traces, "push")

    def per_episode(function) -> np.ndarray:
        return np.array([function(e, slice(0, int(lengths[e]))) for e in range(episodes)],
                        dtype=float)  # fmt: skip

    out: dict[str, np.ndarray] = {}
    if (hip is not None and contact is not None and dt is not None and np.isfinite(standing)
            and np.isfinite(hip).any()):  # fmt: skip
        settle = round(SETTLE_SECONDS / dt)
        out["hop_apex"] = per_episode(lambda e, rows: hop_apex(
            hip[rows, e], contact[rows, e].any(axis=-1), standing,
            None if push is None else np.nan_to_num(push[rows, e]) > 0.5, settle))  # fmt: skip
    if position is not None:
        out["joint_smoothness"] = per_episode(lambda e, rows: joint_smoothness(position[rows, e]))
    if desired is not None:
        out["command_smoothness"] = per_episode(lambda e, rows: smoothness(desired[rows, e]))
    if torque is not None and dt is not None:
        out["torque_rate"] = per_episode(lambda e, rows: torque_rate(torque[rows, e], dt))
    if torque is not None and velocity is not None and torque.shape == velocity.shape:
        out["mechanical_power"] = per_episode(
            lambda e, rows: mechanical_power(torque[rows, e], velocity[rows, e]))  # fmt: skip
    feet = _first(traces, "foot_position")
    if feet is not None and contact is not None and dt is not None \
            and feet.shape[:3] == contact.shape:  # fmt: skip
        out["foot_slip"] = per_episode(lambda e, rows: foot_slip(feet[rows, e], contact[rows, e],
                                                                 dt))  # fmt: skip
    if limits is not None:
        out["time_at_joint_stop"] = per_episode(
            lambda e, rows: joint_stop_share(position[rows, e], *limits))  # fmt: skip
    return {name: out[name] for name in METRICS if name in out}


def run_metrics(traces: dict[str, np.ndarray] | None) -> dict[str, float]:
    """Every metric of :data:`METRICS`, the mean over the episodes that define it; NaN for
    the ones ``traces`` (None: no traces) has no data for."""
    from cpg_actor.training.evaluation import finite_mean

    values = episode_metrics(traces) if traces is not None else {}
    return {name: finite_mean(values[name]) if name in values else float("nan")
            for name in METRICS}  # fmt: skip
