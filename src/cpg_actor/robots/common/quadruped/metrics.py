"""The velocity task's episode metrics as evaluation, ``eval`` and the report print them (every
quadruped's ``Robot.metrics``; light to import)."""

from __future__ import annotations

from cpg_actor.robots.plugin import MetricInfo

METRICS = {
    "speed_error": MetricInfo("forward-speed error", "m/s"),
    "forward_speed": MetricInfo("forward speed", "m/s"),
    "fell": MetricInfo("share of episodes that fell"),
    "episode_seconds": MetricInfo("episode length", "s"),
    "cost_of_transport": MetricInfo(
        "cost of transport", undefined="the robot walked less than 0.1 m forward"
    ),
    "foot_slip": MetricInfo("foot slip speed", "m/s", undefined="no foot was planted"),
    "lin_vel_error": MetricInfo("linear velocity error", "m/s", short="lin vel error"),
    "yaw_rate_error": MetricInfo("yaw-rate error", "rad/s"),
    "lin_vel_offset": MetricInfo("linear velocity offset", "m/s", short="lin vel offset"),
    "yaw_rate_offset": MetricInfo("yaw-rate offset", "rad/s"),
    "duty_factor": MetricInfo("duty factor"),
    "planar_cost_of_transport": MetricInfo(
        "cost of transport (planar)",
        short="CoT",
        undefined="the base's path was shorter than 0.1 m",
    ),
}
