"""What the benchmark scripts share: the provenance line, the write of their Markdown
results and the check of the files they write beside it, running a script with the package of
another source tree. (What the time-to-a-target benchmarks share: ``time_to_target.py``.)"""

from __future__ import annotations

import argparse
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
    """Write ``lines`` to ``path`` atomically (its folder made if needed) and print them."""
    from cpg_actor.files import atomic_write_text

    atomic_write_text("\n".join(lines), Path(path))
    print("\n".join(lines))


def companions(
    parser: argparse.ArgumentParser, output: str | Path, suffixes: tuple[str, ...],
    named: bool, overwrite: bool,
) -> list[Path]:  # fmt: skip
    """The files a benchmark writes beside its report ``output``: its name with each of
    ``suffixes`` (".json", ".png"). Beside a report the user ``named`` (``--output``), a file
    of such a name may be the user's own: one that exists is refused (``parser.error``, one
    line, before anything runs) unless ``overwrite``. Beside the default report they are the
    benchmark's own results (benchmarks/results) and are replaced."""
    output = Path(output)
    paths = [output.with_suffix(suffix) for suffix in suffixes]
    if output in paths:
        parser.error(f"--output {output}: the report would be its own {output.suffix} file; "
                     "give a report name ending in .md")  # fmt: skip
    existing = [str(path) for path in paths if path.exists() or path.is_symlink()]
    if named and existing and not overwrite:
        parser.error(f"--output {output}: {', '.join(existing)} exists and would be replaced "
                     "by the file written beside the report; pass --overwrite to replace it, "
                     "or choose another --output")  # fmt: skip
    return paths


def json_from_tree(src: str | Path, arguments: list[str], show_stderr: bool = False) -> dict:
    """``python *arguments`` with the ``cpg_actor`` package in ``src`` first on its path; the
    last line it prints, parsed as JSON. RuntimeError with the end of its stderr if it fails.
    ``show_stderr``: its stderr goes to ours as it comes (a long run's progress)."""
    path = os.pathsep.join([str(src), os.environ.get("PYTHONPATH", "")])
    done = subprocess.run(
        [sys.executable, *arguments],
        env=dict(os.environ, PYTHONPATH=path),
        stdout=subprocess.PIPE,
        stderr=None if show_stderr else subprocess.PIPE,
        text=True,
    )
    if done.returncode != 0:
        said = "its stderr above" if show_stderr else done.stderr[-3000:]
        raise RuntimeError(f"{' '.join(arguments)} with the package in {src} failed:\n{said}")
    return json.loads(done.stdout.strip().splitlines()[-1])
