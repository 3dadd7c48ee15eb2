"""What benchmark tables record about the machine: the hypervisor's share of the CPU time."""

import math

import pytest

from cpg_actor.machine import cpu_times, stolen_share

STAT = """cpu  100 5 20 800 10 0 3 62 0 0
cpu0 50 2 10 400 5 0 1 31 0 0
intr 12345
"""


def test_cpu_times_reads_the_machine_line(tmp_path):
    stat = tmp_path / "stat"
    stat.write_text(STAT)
    # steal is the 8th value; guest time is already counted in user and left out
    assert cpu_times(stat) == (62, 100 + 5 + 20 + 800 + 10 + 0 + 3 + 62)


def test_cpu_times_without_a_stat_file(tmp_path):
    assert cpu_times(tmp_path / "missing") is None
    (tmp_path / "other").write_text("intr 1 2 3\n")
    assert cpu_times(tmp_path / "other") is None


def test_stolen_share_between_two_readings():
    assert stolen_share((62, 1000), (92, 1200)) == 30 / 200
    assert math.isnan(stolen_share(None, (92, 1200)))
    assert math.isnan(stolen_share((62, 1000), (62, 1000)))  # no time passed


def test_cpu_times_on_this_machine_is_consistent():
    reading = cpu_times()
    if reading is None:
        pytest.skip("no /proc/stat (not Linux)")
    stolen, total = reading
    assert 0 <= stolen <= total
