"""Errors the command line reports in one line, defined apart from the modules that raise
them so that ``cpg_actor.cli`` can catch them without importing torch or a simulator."""

from __future__ import annotations


class MjxUnavailable(ImportError):
    """JAX or MuJoCo XLA is not installed (the message says how to install them)."""


class RenderingUnavailable(RuntimeError):
    """No OpenGL context can be made for MuJoCo's offscreen renderer (no EGL or OSMesa)."""
