"""Carry a reproduction's runs from one sitting (machine) to the next: each finished run's
logs, stage evaluations, traces and config, without checkpoints or TensorBoard files; with
``--unfinished``, each run still training too, with the few checkpoints it needs to go on. A
``cpg-actor sweep`` folder is carried the same way, one reproduction per setting.

    python docs/results/sitting.py save OUT ARCHIVE [--unfinished] [--without-traces]
    python docs/results/sitting.py restore ARCHIVE OUT

``ARCHIVE`` is a folder of the user's (e.g. under the git-ignored ``results/``). ``save`` writes
``ARCHIVE/VARIANT/seedS.tar.gz`` for every finished run of ``OUT`` that has none yet, and
copies ``OUT/reproduce.yaml`` and ``OUT/transfer.json`` (run ``cpg-actor transfer OUT --add``
first, while the checkpoints are there). With ``--unfinished``, an unfinished run goes to
``ARCHIVE/VARIANT/seedS.partial.tar.gz`` (replaced at each save, removed once the run's
finished archive is written) with the checkpoints ``cpg-actor train --resume`` and the stage
evaluations need: the one before the first update, those nearest the stages its training has
passed (``reproduce.yaml``'s ``stage_fractions``) and the newest; a partial archive further
along than the run (a sitting that forgot to restore) is kept. With ``--without-traces``, the
stage evaluations' traces and figures (``eval/stageK/traces.npz`` and PNGs, most of a run's
bytes) stay behind, for a study whose analysis reads other files (``stages.json`` is kept;
the reproduction's own summary then lacks those runs' stage metrics). ``restore`` unpacks each
archived run into ``OUT/runs`` where that run directory does not exist (a finished archive
before a partial one), and copies the two files where ``OUT`` has none, so that the same
``cpg-actor reproduce`` command skips the finished runs, resumes the partial ones and trains the
rest. Nothing that exists is overwritten. For a sweep's ``OUT`` (its marker says so) each
setting's folder goes to ``ARCHIVE/SETTING`` with the sweep's marker beside them, and
``restore`` remakes the sweep's folder, so that the same ``cpg-actor sweep`` command goes on.

The trio's own archives (``docs/results/trio-20M``) are in git history, at
``docs/results/trio-20M/runs`` of commit 2d29b10 (its README says how to restore them).
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tarfile
import tempfile
import zlib
from pathlib import Path

from cpg_actor.api import TrainConfig
from cpg_actor.files import MARKER, SWEEP, describe_os_error, marker_kind
from cpg_actor.safe_yaml import read_yaml
from cpg_actor_studies.reproduction.execute import list_checkpoints, select_stage_checkpoints
from cpg_actor_studies.reproduction.plan import STAGE_FRACTIONS
from cpg_actor_studies.reproduction.results import Results

SKIPPED = {"checkpoints", "tensorboard", ".lock"}
FILES = ("reproduce.yaml", "transfer.json", MARKER)  # the last: the project's marker
PARTIAL = ".partial.tar.gz"
# what reading a damaged archive raises: a truncated gzip stream, a file that is no tar
DAMAGED = (tarfile.TarError, EOFError, zlib.error, OSError)


def kept_checkpoints(run_dir: Path, fractions: tuple[float, ...]) -> list[Path]:
    """An unfinished run's checkpoints to carry: its first, the nearest to each stage its
    training has passed and the newest (``train --resume`` starts from it)."""
    numbered = list_checkpoints(run_dir)
    if not numbered:
        return []
    planned = TrainConfig.load(run_dir / "config.yaml").num_iterations
    newest = max(numbered)
    passed = tuple(f for f in fractions if f * planned <= newest)
    kept = {numbered[min(numbered)], numbered[newest]}  # the newest: what a resume starts from
    if passed:
        kept |= {path for _, _, path in select_stage_checkpoints(numbered, planned, passed)}
    return sorted(kept)


def archived_iteration(partial: Path) -> int:
    """The newest checkpoint's iteration in a partial archive (-1: none); ValueError for a
    damaged one."""
    try:
        with tarfile.open(partial) as tar:
            names = tar.getnames()
    except DAMAGED as error:
        raise ValueError(f"{partial} is damaged ({reason(error)}); move it away to save the "
                         "run again") from None  # fmt: skip
    numbers = [int(digits) for name in names if name.startswith("checkpoints/iter_")
               and (digits := name[len("checkpoints/iter_"):-3]).isdigit()]  # fmt: skip
    return max(numbers, default=-1)


def reason(error: BaseException) -> str:
    """An error's first line, or its type's name where it has no text."""
    if isinstance(error, tarfile.ReadError) and "could not be opened" in str(error):
        return "not a tar or tar.gz file"  # tarfile's message lists each method it tried
    return (str(error).strip() or type(error).__name__).splitlines()[0]


def check_members(tar: tarfile.TarFile, path: Path) -> None:
    """ValueError unless every member of ``tar`` is a file or a folder inside the run
    directory it unpacks to, as :func:`_pack` writes them (no link, device, absolute path or
    ``..``)."""
    for member in tar.getmembers():
        name = member.name
        if not (member.isfile() or member.isdir()):
            raise ValueError(f"{path}: its member {name!r} is not a file or a folder (a link "
                             "or a device); not a run archive of this script")  # fmt: skip
        if name.startswith(("/", "\\")) or ".." in Path(name).parts:
            raise ValueError(f"{path}: its member {name!r} lies outside the run directory; "
                             "not a run archive of this script")  # fmt: skip


def unpack(path: Path, run_dir: Path) -> None:
    """Unpack the archive ``path`` into the new ``run_dir`` through a temporary folder of this
    script's beside it; ValueError for a damaged archive, that folder removed."""
    tmp = Path(tempfile.mkdtemp(dir=run_dir.parent, prefix=".restore-"))
    try:
        tmp.chmod(0o755)  # mkdtemp makes it private; a run directory is not
        with tarfile.open(path) as tar:
            check_members(tar, path)
            tar.extractall(tmp, filter="data")
        tmp.rename(run_dir)
    except DAMAGED as error:
        if isinstance(error, OSError) and error.errno is not None:
            raise  # the disk's (full, unwritable), not the archive's: main says it in one line
        raise ValueError(f"{path} is damaged or not a run archive ({reason(error)}); "
                         "nothing restored from it") from None  # fmt: skip
    finally:
        if tmp.exists():
            shutil.rmtree(tmp)  # this script's own folder, left only where unpacking failed


def _without_traces(info: tarfile.TarInfo) -> tarfile.TarInfo | None:
    """A tar filter leaving out the stage evaluations' traces and figures (``eval/stageK/``)."""
    parts = info.name.split("/")
    stage = len(parts) == 3 and parts[0] == "eval" and parts[1].startswith("stage")
    return None if stage and parts[2].endswith((".npz", ".png")) else info


def _pack(run_dir: Path, target: Path, checkpoints: list[Path], traces: bool = True) -> None:
    target.parent.mkdir(parents=True, exist_ok=True)
    handle, tmp = tempfile.mkstemp(dir=target.parent, suffix=".tmp")
    os.close(handle)
    try:
        with tarfile.open(tmp, "w:gz") as tar:
            for path in sorted(run_dir.iterdir()):
                if path.name not in SKIPPED:
                    tar.add(path, arcname=path.name, filter=None if traces else _without_traces)
            for path in checkpoints:
                tar.add(path, arcname=f"checkpoints/{path.name}")
        os.chmod(tmp, 0o644)  # mkstemp makes it private; an archive to commit is not
        os.replace(tmp, target)
    finally:
        Path(tmp).unlink(missing_ok=True)  # left only where packing failed


def sweep_settings(directory: Path) -> list[Path]:
    """A sweep's folders of one setting each (a reproduction's ``reproduce.yaml`` in each)."""
    return sorted(p for p in directory.iterdir() if (p / "reproduce.yaml").is_file())


def check_folders(source: Path, what: str, target: Path) -> None:
    """ValueError, before anything is written, unless ``source`` is a folder and ``target``
    is a folder or does not exist yet."""
    if not source.is_dir():
        raise ValueError(f"{source} is not a folder; give {what}")
    for path in (target, *target.parents):
        if path.exists() and not path.is_dir():
            raise ValueError(f"{target} is not a folder ({path} is a file); give a folder")


def save(out: Path, archive: Path, unfinished: bool = False, traces: bool = True) -> None:
    check_folders(out, "a reproduction's or a sweep's OUT folder", archive)
    if marker_kind(out) == SWEEP:
        for setting in sweep_settings(out):
            save(setting, archive / setting.name, unfinished, traces)
        archive.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(out / MARKER, archive / MARKER)  # the sweep's: restore remakes it
        return
    if not (out / "runs").is_dir() and not (out / "reproduce.yaml").is_file():
        raise ValueError(f"{out} has neither runs/ nor reproduce.yaml: not a reproduction's "
                         "OUT (cpg-actor reproduce) nor a sweep's")  # fmt: skip
    fractions = stage_fractions(out / "reproduce.yaml")
    for run in (run for runs in Results.load(out).runs.values() for run in runs):
        target = archive / run.variant / f"{run.path.name}.tar.gz"
        partial = archive / run.variant / f"{run.path.name}{PARTIAL}"
        if run.finished and not target.exists():
            _pack(run.path, target, [], traces)
            print(f"saved {target}")
        if run.finished and partial.exists():
            partial.unlink()  # this script's own, superseded by the finished archive
        elif unfinished and not run.finished:
            checkpoints = kept_checkpoints(run.path, fractions)
            newest = int(checkpoints[-1].stem.removeprefix("iter_")) if checkpoints else -1
            if partial.exists() and archived_iteration(partial) > newest:
                print(f"kept {partial}: it is further along (iteration "
                      f"{archived_iteration(partial)} > {newest}); restore it first")  # fmt: skip
            elif checkpoints:
                _pack(run.path, partial, checkpoints, traces)
                print(f"saved {partial} ({len(checkpoints)} checkpoints)")
    archive.mkdir(parents=True, exist_ok=True)  # a reproduction with no run archived yet
    for name in FILES:
        if (out / name).is_file():
            shutil.copyfile(out / name, archive / name)


def stage_fractions(settings: Path) -> tuple[float, ...]:
    """The stage fractions of a reproduction's ``reproduce.yaml`` (the default without one);
    ValueError for one that is not the file ``cpg-actor reproduce`` writes."""
    if not settings.is_file():
        return STAGE_FRACTIONS
    try:
        saved = read_yaml(settings) or {}
        fractions = saved.get("settings", {}).get("stage_fractions") or STAGE_FRACTIONS
        return tuple(float(f) for f in fractions)
    except (AttributeError, TypeError, ValueError) as error:
        raise ValueError(f"{settings} is not the reproduce.yaml cpg-actor reproduce writes "
                         f"({reason(error)})") from None  # fmt: skip


def restore(archive: Path, out: Path) -> None:
    check_folders(archive, "an ARCHIVE folder that sitting.py save wrote", out)
    if marker_kind(archive) == SWEEP:
        for setting in sweep_settings(archive):
            restore(setting, out / setting.name)
        if not (out / MARKER).exists():
            shutil.copyfile(archive / MARKER, out / MARKER)
        return
    packed = sorted(archive.glob("*/seed*.tar.gz"), key=lambda p: p.name.endswith(PARTIAL))
    for path in packed:  # the finished archives first
        seed = path.name.removesuffix(PARTIAL).removesuffix(".tar.gz")
        run_dir = out / "runs" / path.parent.name / seed
        if run_dir.exists():
            print(f"kept {run_dir} (exists)")
            continue
        made = [p for p in run_dir.parents[:3] if not p.exists()]  # VARIANT, runs, OUT
        run_dir.parent.mkdir(parents=True, exist_ok=True)
        try:
            unpack(path, run_dir)
        except ValueError:
            for folder in made:  # the empty folders made for it, this script's own
                if folder.is_dir() and not any(folder.iterdir()):
                    folder.rmdir()
            raise
        print(f"restored {run_dir}" + (" (unfinished: the same command resumes it)"
                                        if path.name.endswith(PARTIAL) else ""))  # fmt: skip
    out.mkdir(parents=True, exist_ok=True)
    for name in FILES:
        if (archive / name).is_file() and not (out / name).exists():
            shutil.copyfile(archive / name, out / name)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=("save", "restore"))
    parser.add_argument("source", type=Path, help="save: OUT; restore: ARCHIVE")
    parser.add_argument("target", type=Path, help="save: ARCHIVE; restore: OUT")
    parser.add_argument("--unfinished", action="store_true",
                        help="save: the runs in training too, with their checkpoints")  # fmt: skip
    parser.add_argument("--without-traces", action="store_true",
                        help="save: without the stage evaluations' traces and figures")  # fmt: skip
    args = parser.parse_args()
    try:
        if args.action == "save":
            save(args.source, args.target, args.unfinished, traces=not args.without_traces)
        else:
            restore(args.source, args.target)
    except ValueError as error:  # a damaged or foreign input: one line
        sys.exit(f"sitting.py {args.action}: error: {error}")
    except OSError as error:  # an unwritable or full disk
        sys.exit(f"sitting.py {args.action}: error: {describe_os_error(error)}")
