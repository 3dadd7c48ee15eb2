"""What a training run writes about itself: a row of scalars per logged iteration in
``metrics.jsonl`` (non-finite values as null) and TensorBoard events (scalars, histograms) in
``tensorboard/``. Without a run directory nothing is written.

A resumed run sets ``purge_step`` (the first step after its checkpoint) before it logs:
TensorBoard then drops the events the interrupted run wrote from that step on, as
``metrics.jsonl`` is cut back, so no step shows twice."""

from __future__ import annotations

import json
import math
import threading
from contextlib import nullcontext
from pathlib import Path

from torch import Tensor

from cpg_actor.files import naming, open_own


def _quiet_writer_thread(args: threading.ExceptHookArgs) -> None:
    """TensorBoard's writer thread dying of an OSError (a full disk) prints no traceback: the
    writer raises the error again in the training thread at its next call, where the command
    line reports it in one line. Any other thread's error goes to the hook before this one."""
    if not (isinstance(args.exc_value, OSError)
            and type(args.thread).__name__ == "_AsyncWriterThread"):  # fmt: skip
        _quiet_writer_thread.previous(args)


class RunLog:
    def __init__(self, run_dir: Path | None, tensorboard: bool = True) -> None:
        self.run_dir = run_dir
        self.use_tensorboard = tensorboard and run_dir is not None
        self._writer = None
        # a resumed run's first step after its checkpoint: TensorBoard drops the points an
        # earlier process logged from there on (they are logged again), as metrics.jsonl is cut
        self.purge_step: int | None = None

    @property
    def writer(self):
        """The TensorBoard writer, opened at first use; None without TensorBoard."""
        if self._writer is None and self.use_tensorboard:
            from torch.utils.tensorboard import SummaryWriter

            if threading.excepthook is not _quiet_writer_thread:
                _quiet_writer_thread.previous = threading.excepthook
                threading.excepthook = _quiet_writer_thread
            with self._tensorboard():
                self._writer = SummaryWriter(
                    log_dir=str(self.run_dir / "tensorboard"), purge_step=self.purge_step
                )
        return self._writer

    def _tensorboard(self):
        """Where an OSError of the TensorBoard writer (which names no file) names its folder."""
        return naming(self.run_dir / "tensorboard") if self.run_dir else nullcontext()

    def write(self, iteration: int, global_step: int, row: dict[str, float]) -> None:
        """Append ``row`` to ``metrics.jsonl`` and to TensorBoard at ``global_step``."""
        if self.run_dir is None:
            return
        self.run_dir.mkdir(parents=True, exist_ok=True)
        record = {"iteration": iteration, "global_step": global_step}
        record.update({k: (None if not math.isfinite(v) else v) for k, v in row.items()})
        path = self.run_dir / "metrics.jsonl"
        with naming(path), open_own(path, "a") as f:  # a link there is refused, not followed
            f.write(json.dumps(record) + "\n")
        if self.writer is not None:
            with self._tensorboard():
                for key, value in row.items():
                    if math.isfinite(value):
                        self.writer.add_scalar(key, value, global_step)

    def scalar(self, tag: str, value: float, step: int) -> None:
        if self.writer is not None:
            with self._tensorboard():
                self.writer.add_scalar(tag, value, step)

    def histograms(self, global_step: int, histograms: dict[str, Tensor]) -> None:
        if self.writer is not None:
            with self._tensorboard():
                for tag, values in histograms.items():
                    self.writer.add_histogram(tag, values, global_step)

    def flush(self) -> None:
        if self._writer is not None:
            with self._tensorboard():
                self._writer.flush()

    def close(self) -> None:
        if self._writer is not None:
            writer, self._writer = self._writer, None
            with self._tensorboard():
                writer.close()
