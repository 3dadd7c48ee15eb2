"""The plain progress line: no ETA until an iteration after the first (which compiles) has
finished, the ETA from those iterations only, and no ``nan`` return before an episode ends."""

import math

from cpg_actor.training import progress
from cpg_actor.training.progress import PlainProgress, return_text


class Clock:
    """A stand-in for time.perf_counter: the test sets the time."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_the_first_line_has_no_eta_and_no_nan_and_the_eta_leaves_out_the_first_iteration(
    monkeypatch, capsys
):
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    bar = PlainProgress("mlp", total=10 * 1024, completed=0, interval=0.0)
    clock.now = 100.0  # the first iteration: compilation
    bar.update(None, completed=1024, sps="10", ret=return_text(math.nan), metrics="")
    first = capsys.readouterr().out
    assert "1,024/10,240 steps (10.0%)" in first and "elapsed 100 s" in first
    assert "ETA after warm-up" in first and "return -" in first and "nan" not in first
    clock.now = 101.0  # two more iterations, 1 s each: 1,024 steps per second since then
    bar.update(None, completed=2048, sps="1,024", ret=return_text(-1.234))
    clock.now = 102.0
    bar.update(None, completed=3072, sps="1,024", ret=return_text(-1.5))
    lines = capsys.readouterr().out.splitlines()
    assert "ETA 8 s" in lines[0] and "return -1.23" in lines[0]  # (10,240 - 2,048) / 1,024
    assert "ETA 7 s" in lines[1] and "return -1.50" in lines[1]
    clock.now = 110.0
    bar.update(None, completed=10 * 1024)
    assert "ETA 0 s" in capsys.readouterr().out


def test_a_resumed_run_waits_for_its_own_first_iteration_too(monkeypatch, capsys):
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    bar = PlainProgress("mlp", total=8192, completed=4096, interval=0.0)
    clock.now = 50.0
    bar.update(None, completed=5120)
    assert "ETA after warm-up" in capsys.readouterr().out
    clock.now = 52.0
    bar.update(None, completed=6144)
    assert "ETA 4 s" in capsys.readouterr().out  # 512 steps per second, 2,048 left
