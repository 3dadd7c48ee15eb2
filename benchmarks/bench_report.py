"""What the benchmark scripts share: the provenance line, the write of their Markdown
results, and running a script with the package of another source tree."""

from __future__ import annotations

import datetime
import json
import os
import subprocess
import sys
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


def json_from_tree(src: str | Path, arguments: list[str]) -> dict:
    """``python *arguments`` with the ``cpg_actor`` package in ``src`` first on its path; the
    last line it prints, parsed as JSON. RuntimeError with the end of its stderr if it fails."""
    path = os.pathsep.join([str(src), os.environ.get("PYTHONPATH", "")])
    done = subprocess.run(
        [sys.executable, *arguments],
        env=dict(os.environ, PYTHONPATH=path),
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        raise RuntimeError(
            f"{' '.join(arguments)} with the package in {src} failed:\n{done.stderr[-3000:]}"
        )
    return json.loads(done.stdout.strip().splitlines()[-1])
