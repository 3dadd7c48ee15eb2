"""MJX's Warp implementation (``env.mjx_impl="warp"``) for the Go1, on Warp's CPU backend here:
the same robot and task as MJX's JAX implementation and the MuJoCo env; a clear line where Warp
is missing or the name is unknown."""

import numpy as np
import pytest

from cpg_actor.robots.common import mjx_runtime as runtime
from cpg_actor.robots.go1 import description as robot
from cpg_actor.robots.go1.config import Go1Config
from cpg_actor.robots.go1.gaits import GO1_GAITS
from cpg_actor.robots.go1.vector import Go1VectorEnv
from extras import MJX, WARP  # noqa: I001 (tests/ is on sys.path)

N, STEPS = 2, 50  # one second of the trot
CONFIG = {"command_range": (0.5, 0.5), "reset_noise": 0.0, "episode_seconds": 2.0}


@pytest.mark.slow
@WARP
def test_the_warp_implementation_trots_as_the_mujoco_env():
    """The trot for a second on MJX through Warp: base height within 2 mm and forward speed
    within 0.03 m/s of the MuJoCo env at every step, the return within 1 % (the tolerances of
    the JAX implementation's agreement test, test_go1_mjx.py)."""
    from cpg_actor.robots.go1.mjx import MjxGo1VectorEnv

    cpu = Go1VectorEnv(N, CONFIG)
    warp = MjxGo1VectorEnv(N, {**CONFIG, "sim": "mjx", "mjx_impl": "warp"})
    assert np.abs(cpu.reset(seed=0)[0] - warp.reset(seed=0)[0]).max() < 1e-6
    actions = GO1_GAITS.open_loop_positions("trot", 0.02, robot.NOMINAL_POSE, N, STEPS, 0.5)
    returns = np.zeros((2, N))
    for action in actions.numpy():
        a, b = cpu.step(action), warp.step(action)
        returns += a[1], b[1]
        assert np.abs(a[4]["base_height"] - b[4]["base_height"]).max() < 2e-3
        assert np.abs(a[4]["forward_speed"] - b[4]["forward_speed"]).max() < 0.03
        assert not a[2].any() and not b[2].any()
    assert np.allclose(returns[1], returns[0], rtol=0.01)
    cpu.close()
    warp.close()


def test_an_unknown_implementation_is_one_line():
    with pytest.raises(ValueError, match="mjx_impl must be one of jax, warp, got 'cuda'"):
        Go1Config(mjx_impl="cuda").validate()


@MJX
def test_warp_missing_says_how_to_install_it(monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_warp(name, *args, **kwargs):
        if name == "warp" or name.startswith("warp."):
            raise ImportError("No module named 'warp'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_warp)
    hint = r'needs NVIDIA Warp: pip install -e "\.\[warp\]"'
    with pytest.raises(runtime.MjxUnavailable, match=hint):
        runtime.check_impl("warp")
