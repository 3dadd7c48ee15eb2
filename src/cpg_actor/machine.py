"""What machine a measurement ran on (for benchmark tables and reproduction reports)."""

from __future__ import annotations

import os
import platform
import signal
import subprocess
import sys
from pathlib import Path

# set by a process for the `cpg-actor` subprocesses it starts (reproduce, sweep): its pid
PARENT_ENV = "CPG_ACTOR_PARENT_PID"


def cpu_model() -> str:
    """The CPU's model name from /proc/cpuinfo, or what ``platform`` knows."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as cpuinfo:
            for line in cpuinfo:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def usable_cores() -> int:
    """Logical cores this process may run on (its CPU affinity), at least 1."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def brief_openmp_spinning(environ) -> None:
    """Set ``GOMP_SPINCOUNT=2000`` in ``environ`` (e.g. ``os.environ``) unless it is set. Only
    effective before torch is first imported: libgomp, torch's OpenMP, reads it when it loads.

    torch's OpenMP threads spin up to 300,000 times at each barrier before they sleep. Alone
    on the machine that spinning only uses idle cores; with runs started side by side it holds
    the cores the other runs' threads wait for, and they all crawl. 2,000 spins cost a run
    alone nothing (``benchmarks/shared_device.py`` times both). The ``cpg-actor`` command and
    the benchmarks that time what it runs set it."""
    environ.setdefault("GOMP_SPINCOUNT", "2000")


def load_average() -> str:
    """The 1, 5 and 15 minute load averages, or "n/a"."""
    if not hasattr(os, "getloadavg"):
        return "n/a"
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def cpu_times(stat: str | Path = "/proc/stat") -> tuple[int, int] | None:
    """(stolen, total) CPU time of the whole machine since boot, in clock ticks, from the
    ``cpu`` line of ``/proc/stat``; None where there is none (not Linux). "Stolen" is the
    time the hypervisor of a virtual machine ran something else while this machine's CPUs
    were ready to run: the share a neighbour on a shared host took."""
    try:
        with open(stat, encoding="utf-8") as lines:
            fields = lines.readline().split()
    except OSError:
        return None
    if len(fields) < 9 or fields[0] != "cpu":
        return None
    # user nice system idle iowait irq softirq steal [guest guest_nice: counted in user]
    ticks = [int(value) for value in fields[1:9]]
    return ticks[7], sum(ticks)


def stolen_share(before: tuple[int, int] | None, after: tuple[int, int] | None) -> float:
    """The share of the machine's CPU time the hypervisor took between two
    :func:`cpu_times` readings (0..1); NaN if either is None or no time passed."""
    if before is None or after is None or after[1] <= before[1]:
        return float("nan")
    return (after[0] - before[0]) / (after[1] - before[1])


def git_commit(path: str | Path | None = None) -> str:
    """The short git commit of the checkout holding ``path`` (default: this package), marked
    "(uncommitted changes)" when the tree differs from it; "unknown" outside a checkout."""
    root = Path(path) if path is not None else Path(__file__).resolve().parent

    def git(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            ["git", "-C", str(root), *args], capture_output=True, text=True, timeout=5, check=False
        )

    try:
        head, dirty = git("rev-parse", "--short", "HEAD"), git("status", "--porcelain")
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    if head.returncode != 0:
        return "unknown"
    return head.stdout.strip() + (" (uncommitted changes)" if dirty.stdout.strip() else "")


def die_with_parent(environ) -> None:
    """In a ``cpg-actor`` started by another with ``PARENT_ENV`` in ``environ``: ask Linux to
    kill this process when that parent dies, even by kill -9 (``PR_SET_PDEATHSIG``), rather
    than leave it training on as an orphan; exit at once if the parent is already gone.
    Elsewhere nothing."""
    parent = environ.pop(PARENT_ENV, None)  # not passed on to what this process starts
    if not parent or not sys.platform.startswith("linux"):
        return
    import ctypes

    pr_set_pdeathsig = 1  # <linux/prctl.h>
    ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, signal.SIGKILL)
    if os.getppid() != int(parent):  # it died before the signal was asked for
        os._exit(1)
