"""JAX and MJX, imported once with this project's settings.

* ``XLA_PYTHON_CLIENT_PREALLOCATE=false``: by default JAX reserves 75 % of a GPU's memory when
  it starts, which leaves torch (the policy, PPO's storage) next to nothing. Set here before
  JAX is first imported, unless the user set it; ``XLA_PYTHON_CLIENT_MEM_FRACTION`` is left to
  the user.
* ``mujoco`` is first imported through :mod:`cpg_actor.robots.common.mujoco_runtime`, which
  chooses the headless OpenGL backend (``MUJOCO_GL``) before it: later rendering works.
* ``mujoco.mjx`` prints a line when its optional Warp backend is missing; that line is
  swallowed (this project uses MJX's JAX implementation).
"""

from __future__ import annotations

import contextlib
import io
import os

from cpg_actor.errors import MjxUnavailable  # noqa: F401 (defined there: the CLI catches it)

# the fields of mjx.Data a step starts from (with ctrl, which the actuator law sets at every
# substep): every other field is derived from them by mjx.step; what a reset replaces and a
# checkpoint saves
STATE_FIELDS = ("qpos", "qvel", "qacc_warmstart")

INSTALL_HINT = (
    'sim="mjx" needs JAX and MuJoCo XLA: pip install -e ".[mjx]" (CPU), and JAX\'s CUDA '
    "build for a GPU (docs/gpu.md)"
)


def load():
    """``(jax, mjx)``; :class:`MjxUnavailable` with the install line if either is missing."""
    os.environ.setdefault("XLA_PYTHON_CLIENT_PREALLOCATE", "false")
    import cpg_actor.robots.common.mujoco_runtime  # noqa: F401  (MUJOCO_GL, then mujoco)

    try:
        import jax

        with contextlib.redirect_stdout(io.StringIO()):  # "Failed to import warp: ..."
            from mujoco import mjx
    except ImportError as error:
        raise MjxUnavailable(f"{INSTALL_HINT} ({error})") from None
    return jax, mjx


def available() -> bool:
    """Whether JAX and MJX can be imported."""
    try:
        load()
    except MjxUnavailable:
        return False
    return True


def check_impl(impl: str) -> None:
    """:class:`MjxUnavailable` with the install line if MJX's ``impl`` cannot run here (its
    ``"warp"`` needs the warp-lang package; MuJoCo's MJX carries the rest)."""
    if impl != "warp":
        return
    try:
        with contextlib.redirect_stdout(io.StringIO()):  # Warp's banner
            import warp  # noqa: F401
    except ImportError as error:
        raise MjxUnavailable(
            f'mjx_impl="warp" needs NVIDIA Warp: pip install -e ".[warp]" ({error})'
        ) from None
