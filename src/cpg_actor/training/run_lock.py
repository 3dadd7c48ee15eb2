"""One writer per run directory: an advisory ``flock`` on ``RUN_DIR/.lock``.

``cpg-actor train`` (new, ``--resume`` or ``--overwrite``) holds it while it writes; a second
writer is refused with the holder's pid, host and start time. The operating system releases a
``flock`` when its process ends, however it ends, so a crashed run never leaves it stuck (the
file stays, the lock does not).
"""

from __future__ import annotations

import datetime
import json
import os
import socket
from pathlib import Path

from cpg_actor.files import LOCK, open_own

LOCK_NAME = LOCK


class RunInUseError(FileExistsError):
    """Another process holds the run directory's lock."""


class RunLock:
    def __init__(self, run_dir: Path) -> None:
        self.path = Path(run_dir) / LOCK_NAME
        self._file = None

    def acquire(self) -> RunLock:
        """Take the lock or raise :class:`RunInUseError` naming the holder; returns self."""
        import fcntl

        self.path.parent.mkdir(parents=True, exist_ok=True)
        handle = open_own(self.path, "a+")  # a link there is refused, never followed
        try:
            fcntl.flock(handle.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.seek(0)
            holder = _describe(handle.read())
            handle.close()
            raise RunInUseError(
                f"run directory {self.path.parent} is in use by {holder}; wait for that "
                "`cpg-actor train` to finish or stop it"
            ) from None
        handle.seek(0)
        handle.truncate()
        info = {
            "pid": os.getpid(),
            "host": socket.gethostname(),
            "since": datetime.datetime.now().isoformat(timespec="seconds"),
        }
        handle.write(json.dumps(info) + "\n")
        handle.flush()
        self._file = handle
        return self

    def release(self) -> None:
        if self._file is not None:
            self._file.close()  # closing the descriptor releases the flock
            self._file = None

    def __enter__(self) -> RunLock:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()


def _describe(text: str) -> str:
    try:
        info = json.loads(text)
        return f"process {info['pid']} on {info['host']} (since {info['since']})"
    except (ValueError, KeyError, TypeError):
        return "another process"
