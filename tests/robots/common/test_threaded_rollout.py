"""ThreadedRollout: the calling thread and its helpers step exactly what one thread steps."""

from __future__ import annotations

import gc
import os
import threading

import numpy as np
import pytest

from cpg_actor.robots.common.mujoco_runtime import CONTROL_SPEC, STATE_SPEC, mujoco
from cpg_actor.robots.common.threaded_rollout import ThreadedRollout, guided_chunks
from cpg_actor.robots.hopper.backends.mujoco_backend import load_model
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.simulation import HopperSimulation

K, SUBSTEPS = 37, 10  # 37: the last chunk is a short one


def hopping_states(num_robots: int) -> np.ndarray:
    """Full physics states of robots in flight, on the ground and in between."""
    sim = HopperSimulation(HopperConfig(), num_robots, num_threads=1)
    rng = np.random.default_rng(0)
    sim.reset_robots(np.arange(num_robots), rng.uniform(-0.1, 0.1, (num_robots, 2)))
    for t in range(30):
        sim.step(sim.desired + 0.4 * np.sin(0.3 * t + np.arange(num_robots))[:, None])
    state = sim.backend.get_state()
    sim.close()
    return state


@pytest.fixture(scope="module")
def setup():
    model = load_model(0.001, 0.8)
    state = hopping_states(K)
    rng = np.random.default_rng(1)
    control = np.repeat(rng.uniform(-1.0, 1.0, (K, 1, model.nu)), SUBSTEPS, axis=1)
    # the reference: MuJoCo's rollout of all K robots on the calling thread
    reference_state = np.zeros((K, SUBSTEPS, state.shape[1]))
    reference_sensors = np.zeros((K, SUBSTEPS, model.nsensordata))
    mujoco.rollout.Rollout(nthread=0).rollout(
        [model] * K, [mujoco.MjData(model)], state, control, control_spec=CONTROL_SPEC,
        nstep=SUBSTEPS, initial_warmstart=None, state=reference_state,
        sensordata=reference_sensors,
    )  # fmt: skip
    return model, state, control, reference_state, reference_sensors


@pytest.mark.parametrize(("threads", "chunk"), [(1, None), (2, None), (3, 5), (4, 1), (2, 64)])
def test_any_threads_and_chunks_step_what_one_thread_steps(setup, threads, chunk):
    model, state, control, reference_state, reference_sensors = setup
    stepper = ThreadedRollout(model, K, threads, chunk)
    next_state = np.full_like(reference_state, np.nan)
    sensors = np.full_like(reference_sensors, np.nan)
    for _ in range(3):  # the helpers serve call after call
        stepper.rollout(state, control, next_state, sensors, CONTROL_SPEC, SUBSTEPS)
        np.testing.assert_array_equal(next_state, reference_state)
        np.testing.assert_array_equal(sensors, reference_sensors)
    no_sensors = np.full_like(reference_state, np.nan)
    stepper.rollout(state, control, no_sensors, None, CONTROL_SPEC, SUBSTEPS)
    np.testing.assert_array_equal(no_sensors, reference_state)
    stepper.close()
    assert mujoco.mj_stateSize(model, STATE_SPEC) == state.shape[1]


def helper_threads() -> int:
    return sum(t.name == "cpg-actor-rollout" and t.is_alive() for t in threading.enumerate())


def test_a_helpers_error_reaches_the_caller_and_the_stepper_goes_on(setup):
    model, state, control, reference_state, _ = setup
    stepper = ThreadedRollout(model, K, 2, chunk_size=4)
    helper = stepper._steppers[1]
    original = helper.__class__.__call__

    def failing(*args):
        raise ArithmeticError("a helper failed")

    helper.__class__ = type("Failing", (helper.__class__,), {"__call__": failing})
    next_state = np.zeros_like(reference_state)
    with pytest.raises(ArithmeticError, match="a helper failed"):
        stepper.rollout(state, control, next_state, None, CONTROL_SPEC, SUBSTEPS)
    # the calling thread stepped every chunk the helper did not take
    np.testing.assert_array_equal(next_state, reference_state)
    helper.__class__ = type("Working", (helper.__class__,), {"__call__": original})
    next_state[:] = 0.0
    stepper.rollout(state, control, next_state, None, CONTROL_SPEC, SUBSTEPS)
    np.testing.assert_array_equal(next_state, reference_state)
    stepper.close()


def test_closed_or_collected_its_helper_threads_stop(setup):
    model, state, control, reference_state, _ = setup
    before = helper_threads()
    stepper = ThreadedRollout(model, K, 3)
    assert helper_threads() == before + 2
    stepper.close()
    stepper.close()  # idempotent
    assert helper_threads() == before
    with pytest.raises(RuntimeError, match="after close"):
        stepper.rollout(state, control, np.zeros_like(reference_state), None, CONTROL_SPEC, 1)

    threads = ThreadedRollout(model, K, 2)._threads  # never closed: collected at once
    gc.collect()
    for thread in threads:
        thread.join(timeout=10)
        assert not thread.is_alive()


def test_threads_and_chunks_must_be_positive(setup):
    with pytest.raises(ValueError, match="num_threads must be >= 1"):
        ThreadedRollout(setup[0], K, 0)
    with pytest.raises(ValueError, match="chunk_size must be >= 1"):
        ThreadedRollout(setup[0], K, 2, chunk_size=0)


@pytest.mark.parametrize(("robots", "threads"), [(1, 1), (37, 2), (256, 2), (1024, 16), (5, 8)])
def test_the_guided_schedule_covers_every_robot_once_in_shrinking_chunks(robots, threads):
    sizes = [size for _, size in guided_chunks(robots, threads)]
    starts = [start for start, _ in guided_chunks(robots, threads)]
    assert starts == [sum(sizes[:i]) for i in range(len(sizes))]  # contiguous, in order
    assert sum(sizes) == robots
    assert all(a >= b for a, b in zip(sizes, sizes[1:], strict=False))  # never growing
    assert all(size >= 4 for size in sizes[:-1])  # none below the minimum but the remainder


def test_the_guided_schedule_hands_out_a_quarter_of_what_is_left_on_two_threads():
    assert [size for _, size in guided_chunks(256, 2)] == [
        64, 48, 36, 27, 21, 15, 12, 9, 6, 5, 4, 4, 4, 1
    ]  # fmt: skip
    assert [size for _, size in guided_chunks(16, 2)] == [4, 4, 4, 4]
    with pytest.raises(ValueError, match="num_threads and min_size must be >= 1"):
        guided_chunks(16, 0)


def test_the_rollout_uses_the_guided_schedule_unless_given_a_chunk_size(setup):
    model = setup[0]
    assert ThreadedRollout(model, K, 2).chunks == tuple(guided_chunks(K, 2))
    assert ThreadedRollout(model, K, 2, chunk_size=16).chunks == ((0, 16), (16, 16), (32, 5))


def test_a_forked_copy_refuses_to_step_instead_of_waiting_forever(setup, monkeypatch):
    model, state, control, reference_state, _ = setup
    stepper = ThreadedRollout(model, K, 2)
    monkeypatch.setattr(os, "getpid", lambda: -1)  # as in a child made by fork
    with pytest.raises(RuntimeError, match="another process"):
        stepper.rollout(state, control, np.zeros_like(reference_state), None, CONTROL_SPEC, 1)
    monkeypatch.undo()
    stepper.close()
