"""Find where Python reads a torch tensor's or a JAX array's value on the host.

On a GPU each such read (``bool(tensor)``, ``.item()``, ``.cpu()``, ``np.asarray(array)``,
...) waits for every queued kernel: in a control loop it makes the host wait for the device
at every step. On a CPU the same reads cost nothing, and neither torch nor JAX reports them
(JAX's ``transfer_guard`` does not flag device-to-host reads on its CPU backend). So
:func:`host_reads` counts them where they happen, on any device: while it is active, the
Python-level conversions of both libraries record their name, then convert as usual. A
loop that records nothing on the CPU does not wait for a GPU either (apart from what the
libraries do inside their C++ code, such as MJX's solver loops on a GPU)::

    with host_reads() as reads:
        runner.rollout.step()
    assert reads == []

A tool for tests and benchmarks: it patches the classes of torch and JAX for the duration of
the block (and numpy's array constructors), in this process, for every thread.
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterator

import numpy as np
import torch

# the conversions that read a value on the host (``cpu`` and ``numpy`` copy a tensor there)
TORCH_READS = ("__bool__", "__float__", "__int__", "__index__", "__array__", "item", "tolist",
               "numpy", "cpu")  # fmt: skip
JAX_READS = ("__bool__", "__float__", "__int__", "__index__", "__array__", "item", "tolist")
# numpy's constructors: on JAX's CPU backend they read an array through the buffer protocol,
# in C, without its ``__array__``; recorded when given a JAX array or a tensor
NUMPY_READS = ("asarray", "array", "asanyarray", "ascontiguousarray")

_INHERITED = object()


def _classes() -> list[tuple[type, tuple[str, ...]]]:
    classes: list[tuple[type, tuple[str, ...]]] = [(torch.Tensor, TORCH_READS)]
    if "jax" in sys.modules:  # JAX's arrays only where JAX is in use
        import jax.numpy as jnp

        classes.append((type(jnp.zeros(())), JAX_READS))
    return classes


@contextlib.contextmanager
def host_reads() -> Iterator[list[str]]:
    """A list that collects ``"<class>.<conversion>"`` (``"numpy.<function>(<class>)"``) for
    every host read in the block."""
    reads: list[str] = []
    patched = []
    classes = _classes()
    device_types = tuple(cls for cls, _ in classes)
    for name in NUMPY_READS:
        original = getattr(np, name)

        def constructor(value, *args, _original=original, _name=name, **kwargs):
            if isinstance(value, device_types):
                reads.append(f"numpy.{_name}({type(value).__name__})")
            return _original(value, *args, **kwargs)

        patched.append((np, name, original))
        setattr(np, name, constructor)
    for cls, names in classes:
        for name in names:
            original = getattr(cls, name)

            def counted(self, *args, _original=original, _name=f"{cls.__name__}.{name}",
                        **kwargs):  # fmt: skip
                reads.append(_name)
                return _original(self, *args, **kwargs)

            patched.append((cls, name, cls.__dict__.get(name, _INHERITED)))
            setattr(cls, name, counted)
    try:
        yield reads
    finally:
        for owner, name, own in reversed(patched):
            if own is _INHERITED:
                delattr(owner, name)
            else:
                setattr(owner, name, own)
