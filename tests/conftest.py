"""Test-session set-up."""

from pathlib import Path

import pytest

# the offscreen-rendering backend (MUJOCO_GL) chosen before any test module imports mujoco:
# mujoco binds it on import, and a test that rendered could otherwise depend on the order
import cpg_actor.robots.common.mujoco_runtime  # noqa: F401

MUJOCO_LOG = Path("MUJOCO_LOG.TXT")


@pytest.fixture(autouse=True, scope="session")
def no_mujoco_log_left_behind():
    """Some tests blow the simulation up on purpose (the env must terminate those episodes),
    and MuJoCo's warning handler then appends to MUJOCO_LOG.TXT in the working directory, the
    repository root. Remove it at the end unless it was there before. (A custom handler via
    ``mujoco.set_mju_user_warning`` made ``mujoco.Renderer`` abort on this machine.)"""
    existed = MUJOCO_LOG.exists()
    yield
    if not existed:
        MUJOCO_LOG.unlink(missing_ok=True)
