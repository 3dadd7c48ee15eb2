"""``mujoco.rollout`` of K robots on n threads, the calling thread one of them.

MuJoCo's own pool (``rollout.Rollout(nthread=n)``) hands the chunks of robots to n worker
threads while the calling thread waits for them. In training the simulator is idle while the
policy acts, so its workers fall asleep between control steps and every step has to wake them
all. Here the calling thread steps chunks itself and ``n - 1`` helper threads join it, each
taking the next chunk from one shared schedule until none is left (so a thread slowed by a busy
neighbour process, or woken late, does fewer). The chunks shrink towards the end of a call
(:func:`guided_chunks`) so that the threads finish together. Each thread has its own
``Rollout(nthread=0)`` and ``MjData``, and ``rollout`` releases the GIL while it steps.

The result does not depend on the threads: a robot's substeps depend on nothing but its own
state and controls, whichever thread runs them (``tests/robots/common/test_threaded_rollout.py``).
"""

from __future__ import annotations

import os
import queue
import threading
import weakref
from collections.abc import Iterator
from typing import NamedTuple

import numpy as np

from cpg_actor.robots.common.mujoco_runtime import mujoco  # MUJOCO_GL chosen before mujoco
from cpg_actor.robots.common.mujoco_runtime import rollout as mj_rollout


class ThreadedRollout:
    """Steps K robots of one ``MjModel`` through ``nstep`` substeps per call.

    Args:
        model: the robots' model.
        num_robots: K, the rows of the state arrays given to :meth:`rollout`.
        num_threads: threads stepping robots, the calling thread included (>= 1).
        chunk_size: robots per ``mujoco.rollout`` call; None (default): the guided schedule
            of :func:`guided_chunks`.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        num_robots: int,
        num_threads: int,
        chunk_size: int | None = None,
    ) -> None:
        if num_threads < 1:
            raise ValueError(f"num_threads must be >= 1, got {num_threads}")
        self.num_robots = int(num_robots)
        self.num_threads = int(num_threads)
        # one schedule, shared by every call: (first row, rows) of each chunk
        self.chunks = tuple(
            guided_chunks(self.num_robots, self.num_threads)
            if chunk_size is None
            else even_chunks(self.num_robots, int(chunk_size))
        )
        self.model = model
        self._models = [model] * self.num_robots
        self._pid = os.getpid()  # a forked child has none of the helper threads
        self._steppers = [ChunkStepper(model, self._models) for _ in range(self.num_threads)]
        self._jobs = [queue.SimpleQueue() for _ in range(self.num_threads - 1)]
        self._done: queue.SimpleQueue = queue.SimpleQueue()
        self._threads = [
            threading.Thread(
                target=_serve,
                args=(jobs, self._done, stepper),
                daemon=True,
                name="cpg-actor-rollout",
            )
            for jobs, stepper in zip(self._jobs, self._steppers[1:], strict=True)
        ]
        for thread in self._threads:
            thread.start()
        # the helpers hold no reference to self: they stop when it is closed or collected
        self._stop = weakref.finalize(self, _stop_helpers, self._jobs)

    def set_model(self, index: int, model: mujoco.MjModel) -> None:
        """Step robot ``index`` with ``model`` from now on: a model of the same sizes (another
        mass, friction or actuator; randomised training)."""
        self._models[index] = model

    def model_of(self, index: int) -> mujoco.MjModel:
        return self._models[index]

    def rollout(
        self,
        state: np.ndarray,
        control: np.ndarray,
        next_state: np.ndarray,
        sensordata: np.ndarray | None,
        control_spec: int,
        nstep: int,
    ) -> None:
        """``mujoco.rollout`` of every robot: from ``state`` (K, nstate) with ``control``
        (K, nstep, ncontrol), the states after each substep into ``next_state``
        (K, nstep, nstate) and the sensors into ``sensordata`` (K, nstep, nsensordata) or
        None. The arrays must be C-contiguous float64 (they are not checked)."""
        if not self._stop.alive:
            raise RuntimeError("rollout() after close()")
        if os.getpid() != self._pid:
            raise RuntimeError(
                "this simulator was made in another process and its stepping threads did not "
                "survive the fork; make the environment in the process that steps it"
            )
        chunks = iter(self.chunks)  # shared: next() holds the GIL
        job = _Job(chunks, state, control, next_state, sensordata, control_spec, nstep)
        for jobs in self._jobs:
            jobs.put(job)
        error = None
        try:
            self._steppers[0](job)
        except BaseException as raised:  # still wait for the helpers: they use the arrays
            error = raised
        for _ in self._jobs:
            helper_error = self._done.get()
            error = error or helper_error
        if error is not None:
            raise error

    def close(self) -> None:
        """Stop the helper threads (idempotent)."""
        self._stop()
        for thread in self._threads:
            thread.join()


def guided_chunks(num_robots: int, num_threads: int, min_size: int = 4) -> list[tuple[int, int]]:
    """``(first row, rows)`` of each chunk of a guided schedule: each chunk ``1 / (2 n)`` of
    the robots not yet handed out, at least ``min_size`` (256 robots on 2 threads: 64, 48,
    36, 27, 21, 15, 12, 9, 6, 5, 4, 4, 4, 1). The large chunks first keep the calls few, the
    small ones last let the threads finish together, so the calling thread seldom waits for
    a helper (``benchmarks/rollout_threads.py`` compares it with fixed chunks)."""
    if num_threads < 1 or min_size < 1:
        raise ValueError(f"num_threads and min_size must be >= 1, got {num_threads} and {min_size}")
    chunks, start = [], 0
    while start < num_robots:
        left = num_robots - start
        size = min(left, max(min_size, -(-left // (2 * num_threads))))
        chunks.append((start, size))
        start += size
    return chunks


def even_chunks(num_robots: int, size: int) -> list[tuple[int, int]]:
    """``(first row, rows)`` of chunks of ``size`` robots, the last one shorter if need be."""
    if size < 1:
        raise ValueError(f"chunk_size must be >= 1, got {size}")
    return [(start, min(size, num_robots - start)) for start in range(0, num_robots, size)]


class _Job(NamedTuple):
    """One ``rollout`` call, shared by the threads: they take chunks from ``chunks``."""

    chunks: Iterator[tuple[int, int]]  # (first row, rows) of each chunk
    state: np.ndarray
    control: np.ndarray
    next_state: np.ndarray
    sensordata: np.ndarray | None
    control_spec: int
    nstep: int


class ChunkStepper:
    """One thread's ``Rollout(nthread=0)`` and ``MjData``, stepping chunks until none is left
    (``benchmarks/rollout_threads.py`` times its calls)."""

    def __init__(self, model: mujoco.MjModel, models: list[mujoco.MjModel]) -> None:
        self.roller = mj_rollout.Rollout(nthread=0)
        self.datas = [mujoco.MjData(model)]
        self.models = models

    def __call__(self, job: _Job) -> None:
        for start, size in job.chunks:
            rows = slice(start, start + size)
            self.roller.rollout(
                self.models[rows], self.datas, job.state[rows], job.control[rows],
                control_spec=job.control_spec, skip_checks=True, nstep=job.nstep,
                initial_warmstart=None, state=job.next_state[rows],
                sensordata=None if job.sensordata is None else job.sensordata[rows],
            )  # fmt: skip


def _serve(jobs: queue.SimpleQueue, done: queue.SimpleQueue, stepper: ChunkStepper) -> None:
    """A helper thread: step chunks of each job until told to stop (None)."""
    while (job := jobs.get()) is not None:
        try:
            stepper(job)
            done.put(None)
        except BaseException as error:  # handed to the calling thread, which raises it
            done.put(error)


def _stop_helpers(job_queues: list[queue.SimpleQueue]) -> None:
    for jobs in job_queues:
        jobs.put(None)
