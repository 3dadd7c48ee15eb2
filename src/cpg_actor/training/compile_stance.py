"""Whether the training loop's compiled calls skip dynamo's guard checks (``ppo.compile``).

Before every call of a compiled function dynamo checks its guards (the inputs' shapes, dtypes
and strides, the global settings, the module attributes the function read), a fixed cost per
call that adds up over the rollout's small calls. Once a runner has made one iteration, every
compiled function of its loop is built for the shapes and settings the loop uses, and they do
not change during a run; with ``ppo.skip_guard_checks`` (CPU only) the calls then skip the
checks (``torch.compiler.set_stance(skip_guard_eval_unsafe=True)``: the guards that tell the
cached variants of a function apart are still checked, a call that matches no variant raises
instead of compiling one, and the compiled code asserts its inputs' sizes and strides). The
same compiled code runs, so training computes the same numbers
(``tests/training/test_runner.py``; the speed-up is measured by ``benchmarks/guard_checks.py``).
After dynamo has forgotten its compiled functions (a new compiled :class:`~cpg_actor.ppo.PPO`
in this process) the next iteration checks them again.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import torch

from cpg_actor.ppo import PPOConfig, compile_generation


class CompileStance:
    """The guard-check stance of one runner's compiled calls (see the module docstring)."""

    def __init__(self, config: PPOConfig, device: torch.device) -> None:
        self.config = config
        self.device = device
        # compile_generation() when the runner's compiled functions were last all built and
        # run with their guards checked (after an iteration); None: not yet
        self.warm_generation: int | None = None

    def mark_warm(self) -> None:
        """A whole iteration has run: every compiled function of the loop is built."""
        self.warm_generation = compile_generation()

    @property
    def skips_guard_checks(self) -> bool:
        """Whether :meth:`calls` skips dynamo's guard checks now."""
        cfg = self.config
        warm = self.warm_generation is not None and self.warm_generation == compile_generation()
        return cfg.compile and cfg.skip_guard_checks and self.device.type == "cpu" and warm

    @contextlib.contextmanager
    def calls(self) -> Iterator[None]:
        """The context of the rollout's and the update's compiled calls."""
        if not self.skips_guard_checks:
            yield
            return
        with torch.compiler.set_stance(skip_guard_eval_unsafe=True):
            try:
                yield
            except RuntimeError as error:
                if "skip_guard_eval_unsafe" not in str(error):
                    raise
                raise RuntimeError(
                    "a compiled function of the training loop had to be compiled again after "
                    "the run's first iteration, which ppo.skip_guard_checks assumes never "
                    "happens (did something call torch.compiler.reset() or change torch's "
                    "threads mid-run?); train with --set ppo.skip_guard_checks=false. "
                    f"torch: {error}"
                ) from None
