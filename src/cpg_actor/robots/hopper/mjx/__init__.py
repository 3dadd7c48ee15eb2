"""The hopper on MuJoCo XLA (MJX): N hoppers stepped together by JAX on its default device (a
GPU where JAX has one, else the CPU), with observations, rewards and done flags handed to
torch through DLPack, never through the host.

``pip install -e ".[mjx]"`` installs JAX and mujoco-mjx (CPU); for an NVIDIA GPU also install
JAX's CUDA build (``docs/gpu.md``). Nothing here is imported until ``sim="mjx"`` is asked for.

* :mod:`cpg_actor.robots.common.mjx_runtime`: imports JAX and MJX with the settings this
  project needs (no GPU pre-allocation next to torch), or says how to install them.
* :mod:`dynamics`: the environment as pure, jitted JAX functions (reset, control step with the
  actuator law at every substep, observation, reward, termination, autoreset).
* :mod:`vector`: :class:`MjxHopperVectorEnv`, the Gymnasium vector env (numpy in and out) and
  the trainer's tensor contract (torch in and out, on the device).
"""

from __future__ import annotations


def __getattr__(name: str):
    if name == "MjxHopperVectorEnv":
        from cpg_actor.robots.hopper.mjx.vector import MjxHopperVectorEnv

        return MjxHopperVectorEnv
    raise AttributeError(name)


__all__ = ["MjxHopperVectorEnv"]
