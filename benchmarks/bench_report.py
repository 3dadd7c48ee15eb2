"""What the benchmark scripts' Markdown results share: the provenance line and the write."""

from __future__ import annotations

import datetime
from pathlib import Path

from cpg_actor.machine import git_commit


def measured(command: str) -> str:
    """``Measured <UTC time> at commit <commit> with `command```."""
    now = datetime.datetime.now(datetime.timezone.utc)
    return f"Measured {now:%Y-%m-%d %H:%M} UTC at commit {git_commit()} with `{command}`"


def write(path: str | Path, lines: list[str]) -> None:
    """Write ``lines`` to ``path`` (its folder made if needed) and print them."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines))
    print("\n".join(lines))
