"""MuJoCo as every robot's MuJoCo env uses it: imported once the offscreen-rendering
backend is chosen, the state layouts of ``mj_getState``, an offscreen renderer and the
thread count of a batch.

Headless rendering: ``MUJOCO_GL`` must be chosen before ``mujoco`` is first imported. On Linux
without a ``DISPLAY`` this module defaults it (:func:`headless_gl`) to ``egl`` where libEGL is
installed, else ``osmesa`` where libOSMesa is, else ``disable``: with no OpenGL library at all
``import mujoco`` would fail (PyOpenGL cannot load EGL), and training needs no rendering. A
process that imported ``mujoco`` before this module keeps the backend ``mujoco`` chose then
(:func:`gl_backend`); where that is GLFW without a display, :func:`offscreen_renderer` refuses
rather than let GLFW fail (the second failed ``mujoco.Renderer`` aborts the interpreter).
"""

from __future__ import annotations

import ctypes.util
import os
import sys


def headless_gl(find_library=ctypes.util.find_library) -> str:
    """The ``MUJOCO_GL`` backend for a machine without a display: egl, osmesa or disable."""
    if find_library("EGL"):
        return "egl"
    if find_library("OSMesa"):
        return "osmesa"
    return "disable"


if sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", headless_gl())

import mujoco  # noqa: E402
from mujoco import rollout  # noqa: E402, F401  (threaded_rollout's)

from cpg_actor.machine import usable_cores  # noqa: E402
from cpg_actor.robots.common.video import RenderingUnavailable  # noqa: E402

STATE_SPEC = mujoco.mjtState.mjSTATE_FULLPHYSICS.value  # [time, qpos, qvel, (act, ...)]
CONTROL_SPEC = mujoco.mjtState.mjSTATE_CTRL.value  # desired joint positions
TORQUE_SPEC = mujoco.mjtState.mjSTATE_QFRC_APPLIED.value  # joint torques (actuator_law "coast")
PUSH_SPEC = mujoco.mjtState.mjSTATE_XFRC_APPLIED.value  # forces on bodies (a perturbation's push)


def add_mass(model: mujoco.MjModel, body: str, mass: float,
             scratch: mujoco.MjData | None = None) -> None:  # fmt: skip
    """``mass`` kg added to ``body`` of ``model`` at its centre of mass (a point mass there
    leaves its inertia about the centre as it is), and the model's derived constants
    recomputed, as compiling it with that mass would (:func:`mujoco.mj_setConst`), in
    ``scratch`` (an MjData of the model's sizes, reset first; None: a new one)."""
    model.body_mass[model.body(body).id] += mass
    if scratch is None:
        scratch = mujoco.MjData(model)
    else:  # as a new MjData starts
        mujoco.mj_resetData(model, scratch)
    mujoco.mj_setConst(model, scratch)


def gl_backend() -> str:
    """The OpenGL backend ``mujoco`` bound when it was imported (``egl``, ``osmesa``, ``glfw``,
    ...; ``disable`` for none): what ``MUJOCO_GL`` was then, whatever it is now."""
    context = getattr(mujoco, "GLContext", None)
    return context.__module__.rsplit(".", 1)[-1] if context is not None else "disable"


def offscreen_renderer(model: mujoco.MjModel, width: int, height: int) -> mujoco.Renderer:
    """A ``mujoco.Renderer`` of ``width`` x ``height`` (the model's offscreen buffer grown to
    fit); :class:`~cpg_actor.robots.common.video.RenderingUnavailable` where no OpenGL context can
    be made (``MUJOCO_GL`` is ``disable``, its library does not load, or ``mujoco`` was imported
    before it was chosen and bound GLFW, which needs a display)."""
    needs = "rendering needs libEGL (MUJOCO_GL=egl) or OSMesa (MUJOCO_GL=osmesa)"
    linux_without_display = sys.platform.startswith("linux") and not os.environ.get("DISPLAY")
    if gl_backend() == "glfw" and linux_without_display:
        raise RenderingUnavailable(
            "MuJoCo cannot render here (MUJOCO_GL=glfw: mujoco was imported before MUJOCO_GL "
            "was chosen, and GLFW needs a display); set MUJOCO_GL before mujoco is first "
            f"imported, or import cpg_actor first; {needs}"
        )
    model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
    model.vis.global_.offheight = max(model.vis.global_.offheight, height)
    try:
        return mujoco.Renderer(model, height=height, width=width)
    except Exception as error:  # whatever the GL layer raises (FatalError, AttributeError, ...)
        raise RenderingUnavailable(
            f"MuJoCo cannot render here (MUJOCO_GL={gl_backend()}: "
            f"{type(error).__name__}: {error}); {needs}"
        ) from error


def default_threads(num_robots: int, robots_per_thread: int = 8) -> int:
    """Threads for K robots: the cores this process may use, at least ``robots_per_thread``
    robots per thread (fewer, and handing them to a thread costs more than it saves: 8 with a
    control step per ``rollout`` call, 16 with a substep per call, ``actuator_law="coast"``)."""
    return max(1, min(usable_cores(), num_robots // robots_per_thread))
