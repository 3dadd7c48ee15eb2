"""Carry a reproduction's finished runs from one sitting (machine) to the next: their logs,
stage evaluations, traces and config, without checkpoints or TensorBoard files.

    python docs/results/trio-20M/sitting.py save OUT ARCHIVE
    python docs/results/trio-20M/sitting.py restore ARCHIVE OUT

``ARCHIVE`` is a folder of the user's, outside ``docs/`` (e.g. under the git-ignored
``results/``). The trio's own archives are in git history, at ``docs/results/trio-20M/runs`` of
commit 2d29b10 (its README says how to restore them).

``save`` writes ``ARCHIVE/VARIANT/seedS.tar.gz`` for every finished run of ``OUT`` that has
none yet, and copies ``OUT/reproduce.yaml`` and ``OUT/transfer.json`` (run ``cpg-actor transfer
OUT --add`` first, while the checkpoints are there). ``restore`` unpacks each archived run into
``OUT/runs`` where that run directory does not exist, and copies the two files where ``OUT`` has
none, so that the same ``cpg-actor reproduce`` command skips the finished runs and trains the
rest. Nothing that exists is overwritten.
"""

from __future__ import annotations

import os
import shutil
import sys
import tarfile
import tempfile
from pathlib import Path

from cpg_actor.experiments.results import Results

SKIPPED = {"checkpoints", "tensorboard", ".lock"}
FILES = ("reproduce.yaml", "transfer.json", ".cpg-actor-run")  # the last: the project's marker


def save(out: Path, archive: Path) -> None:
    for run in (run for runs in Results.load(out).runs.values() for run in runs):
        run_dir = run.path
        target = archive / run.variant / f"{run_dir.name}.tar.gz"
        if not run.finished or target.exists():
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        handle, tmp = tempfile.mkstemp(dir=target.parent, suffix=".tmp")
        os.close(handle)
        with tarfile.open(tmp, "w:gz") as tar:
            for path in sorted(run_dir.iterdir()):
                if path.name not in SKIPPED:
                    tar.add(path, arcname=path.name)
        os.replace(tmp, target)
        print(f"saved {target}")
    for name in FILES:
        if (out / name).is_file():
            shutil.copyfile(out / name, archive / name)


def restore(archive: Path, out: Path) -> None:
    for packed in sorted(archive.glob("*/seed*.tar.gz")):
        run_dir = out / "runs" / packed.parent.name / packed.name.removesuffix(".tar.gz")
        if run_dir.exists():
            print(f"kept {run_dir} (exists)")
            continue
        run_dir.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=run_dir.parent, prefix=".restore-"))
        tmp.chmod(0o755)  # mkdtemp makes it private; a run directory is not
        with tarfile.open(packed) as tar:
            tar.extractall(tmp, filter="data")
        tmp.rename(run_dir)
        print(f"restored {run_dir}")
    for name in FILES:
        if (archive / name).is_file() and not (out / name).exists():
            shutil.copyfile(archive / name, out / name)


if __name__ == "__main__":
    if len(sys.argv) != 4 or sys.argv[1] not in ("save", "restore"):
        sys.exit("usage: sitting.py save OUT ARCHIVE | sitting.py restore ARCHIVE OUT")
    action, first, second = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])
    save(first, second) if action == "save" else restore(first, second)
