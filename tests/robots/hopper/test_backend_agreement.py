"""MuJoCo and PyBullet agree with each other and with hand calculations.

Tolerances: free fall and frictionless statics are exact up to the integrator (1e-6); standing
with friction and the open-loop trajectory involve two different contact models (MuJoCo's soft
constraints, Bullet's rigid ones), so they agree to millimetres and hundredths of a radian.
"""

from __future__ import annotations

import numpy as np
import pytest

from cpg_actor.robots.anymal_leg import kinematics as leg_kinematics
from cpg_actor.robots.hopper import description as robot
from cpg_actor.robots.hopper import kinematics

from .helpers import NOMINAL, SIMS, backend_for, place, simulate

DT = 0.001
G = robot.GRAVITY


def both(**overrides):
    return {sim: backend_for(sim, **overrides) for sim in SIMS}


def test_total_mass_agrees():
    for backend, _, _ in both().values():
        assert backend.total_mass() == pytest.approx(robot.TOTAL_MASS, abs=1e-9)
        backend.close()


def test_free_fall_of_the_rail():
    """From 1 m, joints held by the PD law: the hip falls as h - g t^2 / 2."""
    height, substeps = 1.0, 300
    logs = {}
    for sim, (backend, _, _) in both().items():
        place(backend, NOMINAL, hip_height=height)
        logs[sim], _ = simulate(backend, lambda t: NOMINAL, substeps, DT)
        backend.close()
    n = np.arange(1, substeps + 1)
    t = n * DT
    # semi-implicit Euler (both simulators): z_n = h - g dt^2 n (n + 1) / 2, exactly
    euler = height - G * DT**2 * n * (n + 1) / 2
    for sim, log in logs.items():
        np.testing.assert_allclose(log[:, 0], euler, atol=1e-9, err_msg=sim)
        # the continuous solution, within the integrator's first-order error g dt t / 2
        np.testing.assert_allclose(log[:, 0], height - G * t**2 / 2, atol=G * DT * t[-1] / 2 + 1e-9)
        np.testing.assert_allclose(log[:, 1:], np.tile(NOMINAL, (substeps, 1)), atol=1e-9)
    np.testing.assert_allclose(logs["mujoco"], logs["pybullet"], atol=1e-9)


def test_static_torques_standing_match_the_hand_calculation():
    """Frictionless floor (the ground force is vertical) and stiff gains (pose ~ nominal)."""
    torques, poses = {}, {}
    for sim, (backend, _, _) in both(foot_friction=0.0, kp=1000.0, kd=20.0).items():
        place(backend, NOMINAL)
        qpos, torque = simulate(backend, lambda t: NOMINAL, 2000, DT)
        assert np.abs(backend.qvel).max() < 1e-4, sim  # settled
        torques[sim], poses[sim] = torque[-100:].mean(axis=0), qpos[-1, 1:]
        backend.close()
        # the kinematics module's statics at the pose actually reached
        np.testing.assert_allclose(
            torques[sim], kinematics.standing_torques(poses[sim]), atol=0.01, err_msg=sim
        )
    np.testing.assert_allclose(torques["mujoco"], torques["pybullet"], atol=0.01)
    # By hand, nominal pose. Ground force = whole weight M g = 3.40697 * 9.81 = 33.42 N at the
    # foot, x_foot - x_KFE = 0.1743 - (-0.0339) = 0.2082 m -> 6.958 N m; minus the shank and
    # adapter weights in front of the knee: 9.81 * (0.2072 * 0.0280 + 0.14017 * 0.1872)
    # = 0.314 N m -> tau_KFE = 6.64 N m. HFE: 33.42 * (0.1743 - 0.0635) = 3.704 N m minus the
    # thigh, shank and adapter weights about the HFE axis: 9.81 * (1.63498 * -0.0872 + 0.2072 *
    # -0.0693 + 0.14017 * 0.0899) = -1.415 N m -> tau_HFE = 5.12 N m.
    for sim in SIMS:
        np.testing.assert_allclose(torques[sim], [5.12, 6.64], atol=0.15, err_msg=sim)
    np.testing.assert_allclose(kinematics.standing_torques(NOMINAL), [5.12, 6.64], atol=0.01)


def test_standing_with_friction_agrees():
    """Default config: the stuck foot takes a horizontal force too; both simulators agree."""
    logs = {}
    for sim, (backend, _, _) in both().items():
        place(backend, NOMINAL)
        logs[sim] = simulate(backend, lambda t: NOMINAL, 1500, DT)
        backend.close()
    (q_mj, tau_mj), (q_pb, tau_pb) = logs["mujoco"], logs["pybullet"]
    assert abs(q_mj[-1, 0] - q_pb[-1, 0]) < 2e-3  # hip height, m
    np.testing.assert_allclose(q_mj[-1, 1:], q_pb[-1, 1:], atol=0.01)  # joints, rad
    np.testing.assert_allclose(tau_mj[-100:].mean(0), tau_pb[-100:].mean(0), atol=0.3)  # N m


def test_open_loop_sinusoid_agrees():
    """2 Hz squat-and-extend (short flight phases) for 1 s of desired positions."""

    def desired(t):
        return NOMINAL + np.array([0.3, -0.6]) * np.sin(2 * np.pi * 2.0 * t)

    logs = {}
    for sim, (backend, _, _) in both().items():
        place(backend, NOMINAL)
        logs[sim], _ = simulate(backend, desired, 1000, DT)
        backend.close()
    diff = logs["mujoco"] - logs["pybullet"]
    joint_rms = np.sqrt(np.mean(diff[:, 1:] ** 2, axis=0))
    hip_rms = np.sqrt(np.mean(diff[:, 0] ** 2))
    assert (joint_rms < 0.03).all(), joint_rms
    assert np.abs(diff[:, 1:]).max() < 0.1
    assert hip_rms < 0.01, hip_rms
    assert np.abs(diff[:, 0]).max() < 0.03
    assert np.ptp(logs["mujoco"][:, 0]) > 0.15  # it really moved


def test_foot_state_and_contact_match_kinematics():
    for sim, (backend, _, _) in both().items():
        place(backend, NOMINAL)
        simulate(backend, lambda t: NOMINAL, 50, DT)
        assert backend.contact().tolist() == [True], sim
        place(backend, NOMINAL, hip_height=0.8)
        simulate(backend, lambda t: NOMINAL + [0.5 * t * 20, -t * 20], 30, DT)
        assert backend.contact().tolist() == [False], sim
        pos, vel = backend.foot_state()
        q, v = backend.qpos[0], backend.qvel[0]
        foot = leg_kinematics.foot_position(q[1:])
        foot_vel = leg_kinematics.foot_velocity(q[1:], v[1:])
        np.testing.assert_allclose(pos[0, [0, 2]], [foot[0], q[0] + foot[1]], atol=1e-6)
        np.testing.assert_allclose(vel[0, [0, 2]], [foot_vel[0], v[0] + foot_vel[1]], atol=1e-5)
        assert abs(vel[0, 1]) < 1e-9 and np.abs(v[1:]).max() > 0.5, sim
        backend.close()
