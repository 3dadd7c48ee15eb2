"""The Go1 on MJX (``sim="mjx"``, JAX's CPU backend here): the same robot and task as the MuJoCo
env, as ANYmal's: identical first observations, then an open-loop trot over a whole 2 s
episode within ANYmal's tolerances (``tests/robots/anymal/test_anymal_mjx.py``), the episode's
end and metrics, and an exact resume."""

import numpy as np
import pytest

from cpg_actor.robots.common import mjx_runtime as runtime
from cpg_actor.robots.go1 import description as robot
from cpg_actor.robots.go1.gaits import GO1_GAITS
from cpg_actor.robots.go1.vector import Go1VectorEnv

if not runtime.available():
    pytest.skip('the MJX backend needs pip install -e ".[mjx]"', allow_module_level=True)

from cpg_actor.robots.go1.mjx import MjxGo1VectorEnv  # noqa: E402

N = 2
STEPS = 100  # one episode
# no reset noise: both envs start from the same pose; the drive of a 0.5 m/s command
CONFIG = {"command_range": (0.5, 0.5), "reset_noise": 0.0, "episode_seconds": 2.0}


@pytest.mark.slow
def test_an_open_loop_trot_agrees_with_the_mujoco_env():
    """Same first observation; then the trot for one episode: the per-step reward within 10 % of
    the MuJoCo env's mean reward and the return within 1 %, base height within 2 mm, forward
    speed within 0.03 m/s, the same feet on the ground in 98 % of the steps, the same episode
    end and its metrics; a saved state continues exactly."""
    cpu, mjx = Go1VectorEnv(N, CONFIG), MjxGo1VectorEnv(N, {**CONFIG, "sim": "mjx"})
    obs_cpu, _ = cpu.reset(seed=0)
    obs_mjx, _ = mjx.reset(seed=0)
    assert np.abs(obs_cpu - obs_mjx).max() < 1e-6
    actions = GO1_GAITS.open_loop_positions("trot", 0.02, robot.NOMINAL_POSE, N, STEPS, 0.5)
    rewards, heights, speeds, same_feet = [], [], [], []
    for step, action in enumerate(actions.numpy()):
        if step == STEPS // 2:
            saved, rest = mjx.get_state(), actions.numpy()[step:]
        a, b = cpu.step(action), mjx.step(action)
        rewards.append((a[1], b[1]))
        heights.append((a[4]["base_height"], b[4]["base_height"]))
        speeds.append((a[4]["forward_speed"], b[4]["forward_speed"]))
        same_feet.append(np.all(a[4]["contact"] == b[4]["contact"], axis=1))
        assert not a[2].any() and not b[2].any()  # no falls
        assert np.array_equal(a[3], b[3])  # truncated together
    rewards, heights, speeds = (np.array(x) for x in (rewards, heights, speeds))
    # per step within 10 % of the mean reward (a contact event's penalty differs by a few
    # percent between the simulators' float32 and float64 contacts, by CPU), the return within 1 %
    assert np.abs(rewards[:, 0] - rewards[:, 1]).max() < 0.1 * np.abs(rewards[:, 0]).mean()
    assert np.allclose(rewards[:, 1].sum(0), rewards[:, 0].sum(0), rtol=0.01)
    assert np.abs(heights[:, 0] - heights[:, 1]).max() < 2e-3
    assert np.abs(speeds[:, 0] - speeds[:, 1]).max() < 0.03
    assert np.mean(same_feet) > 0.98
    metrics_cpu, metrics_mjx = a[4]["episode_metrics"], b[4]["episode_metrics"]
    assert np.all(metrics_mjx["episode_seconds"] == 2.0) and np.all(metrics_mjx["fell"] == 0)
    for name in ("speed_error", "forward_speed", "cost_of_transport", "foot_slip"):
        assert np.allclose(metrics_mjx[name], metrics_cpu[name], rtol=0.05, atol=0.01), name
    last = b[0]
    mjx.set_state(saved)
    for action in rest:
        again = mjx.step(action)
    assert np.array_equal(again[0], last)
    cpu.close()
    mjx.close()
