"""Files the project writes, and the directories it makes (no torch: the CLI imports this).

* Atomic writes: a hidden temporary name next to the target (``.NAME.tmpPID``), then
  ``os.replace``; a write that fails says which file it was writing.
* Links: a file the project writes in place (appends to, locks) or as a temporary is never
  written through a symbolic link: a link there is refused (one line), its target untouched.
  Nor is a folder the project writes its outputs into (a run directory, its ``checkpoints``,
  ``tensorboard``, ``eval`` and ``export``, a results or sweep directory and its folders):
  a link there may lead into a folder of the user's, so it is refused (one line) before
  anything is written (:func:`refuse_linked_folders`).
* The marker ``.cpg-actor-run``, written when the project creates a run directory (``train``),
  a results directory (``reproduce``, a ``sweep``'s setting) or a sweep directory, names what
  made it. ``--overwrite`` deletes only in a directory carrying the marker of its kind, and
  only files whose names the project writes there (and the temporaries of those names); a
  directory holding anything else (a user's file, a link, a folder of unknown name) is
  refused whole, so a refused command deletes and writes nothing.
"""

from __future__ import annotations

import errno
import json
import os
import re
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO

MARKER = ".cpg-actor-run"
MARKER_FORMAT = "cpg-actor-directory"
RUN = "run"  # a `cpg-actor train` run directory
RESULTS = "results"  # a `cpg-actor reproduce` (or one `sweep` setting's) results directory
SWEEP = "sweep"  # a `cpg-actor sweep` directory: its summary and a results directory per setting
LOCK = ".lock"  # the run's lock file (cpg_actor.training.run_lock)

TEMPORARY = re.compile(r"^\.(?P<name>.+)\.tmp(?P<pid>\d+)$")  # an atomic write's ".NAME.tmpPID"

# what the project writes in each kind of directory: (folder, names), both regular expressions
# matched against the whole relative path (folder "": the directory itself), and the temporary
# file of an atomic write of each (a write a killed process left: ".NAME.tmpPID" of one of
# those names, never of another); then the folders it makes
_EVAL = r"traces\.npz|training_curves\.png|traces\.png|gait_diagram\.png|forward_speed\.png"
_RUN_FILES = (
    ("", rf"{re.escape(MARKER)}|{re.escape(LOCK)}|config\.yaml|metrics\.jsonl|warm_start\.json"
         r"|gait\.yaml|reproduce_run\.json|curves\.(png|json)"),
    ("checkpoints", r"(iter_\d+|last)\.pt"),
    ("tensorboard", r"events\.out\.tfevents\.[^/]+"),
    ("eval", rf"{_EVAL}|stages\.json"),
    (r"eval/stage\d+", _EVAL),
    ("export", r"policy\.(onnx|pt)(\.initial_state\.npy|\.robot\.xml)?"),
)  # fmt: skip
_RUN_FOLDERS = (r"checkpoints", r"tensorboard", r"eval", r"eval/stage\d+", r"export")
_RESULTS_FILES = (
    ("", rf"{re.escape(MARKER)}|reproduce\.yaml|summary\.json|report\.md"
         r"|open_loop_floor\.json|transfer\.json"),
    ("logs", r"[^/]+\.log"),
    ("figures", r"[^/]+\.(png|pdf)"),
)  # fmt: skip
_RESULTS_FOLDERS = (r"logs", r"figures", r"runs", r"runs/[^/]+")
_SWEEP_FILES = (("", rf"{re.escape(MARKER)}|sensitivity\.(md|json|png)"),)


def _files(patterns: tuple[tuple[str, str], ...]) -> re.Pattern:
    """One expression for ``patterns`` (folder, names) and their temporaries."""
    return re.compile("|".join(
        f"{folder + '/' if folder else ''}(({names})|\\.({names})\\.tmp\\d+)"
        for folder, names in patterns))  # fmt: skip


KINDS = {
    RUN: (_files(_RUN_FILES), re.compile("|".join(_RUN_FOLDERS))),
    RESULTS: (_files(_RESULTS_FILES), re.compile("|".join(_RESULTS_FOLDERS))),
    SWEEP: (_files(_SWEEP_FILES), re.compile("(?!)")),
}
# the project directories inside one of a kind: where, and their kind (checked as that kind)
_NESTED = {
    RESULTS: (re.compile(r"runs/[^/]+/seed\d+"), RUN),
    SWEEP: (re.compile(r"[^/]+"), RESULTS),
}
_NAMES = {RUN: "run directory", RESULTS: "results directory", SWEEP: "sweep directory"}
_MADE_BY = {RUN: "`cpg-actor train`", RESULTS: "`cpg-actor reproduce` or `sweep`",
            SWEEP: "`cpg-actor sweep`"}  # fmt: skip
# a file every directory of the kind holds (the sign of one made before the marker existed)
_SETTINGS = {RUN: "config.yaml", RESULTS: "reproduce.yaml", SWEEP: "sensitivity.json"}
# the files `train` writes while it runs: their temporaries are removed at the next start
_TRAIN_WRITES = re.compile(r"config\.yaml|metrics\.jsonl|warm_start\.json|gait\.yaml")
_CHECKPOINT_WRITES = re.compile(r"(iter_\d+|last)\.pt")


# -- atomic writes ------------------------------------------------------------------------------
def temporary_path(path: Path) -> Path:
    """The hidden name an atomic write of ``path`` goes through first."""
    return path.with_name(f".{path.name}.tmp{os.getpid()}")


def new_temporary(path: Path) -> Path:
    """:func:`temporary_path`, with nothing there: one a killed process of this pid left (a
    file, or a link that writing it would follow) is removed."""
    tmp = temporary_path(path)
    tmp.unlink(missing_ok=True)
    return tmp


@contextmanager
def naming(path: Path) -> Iterator[None]:
    """An OSError raised inside that names no file, or a temporary one, names ``path``."""
    try:
        yield
    except OSError as error:
        named = error.filename is not None and not TEMPORARY.match(Path(str(error.filename)).name)
        if named or error.errno is None:
            raise
        raise OSError(error.errno, error.strerror, str(path)) from None


class _Writes:
    """A file's ``write`` that keeps the OSError it raised: a writer that turns it into
    another error (torch's zip writer raises a RuntimeError on a full disk) loses the cause."""

    def __init__(self, file: IO[bytes]) -> None:
        self.file = file
        self.error: OSError | None = None

    def write(self, data) -> int:
        try:
            return self.file.write(data)
        except OSError as error:
            self.error = error
            raise

    def flush(self) -> None:
        self.file.flush()

    def __getattr__(self, name: str):  # the rest of the file's interface (seek, tell, ...)
        return getattr(self.file, name)


def _no_follow(path: str, flags: int) -> int:
    """``open``'s opener for a file the project writes: a link there is an error, never
    followed (the file it points to is someone else's)."""
    return os.open(path, flags | os.O_NOFOLLOW, 0o666)


def refuse_link(path: Path) -> None:
    """FileExistsError (one line) if ``path`` is a symbolic link: the project writes or locks
    its own files there, never through a link."""
    if Path(path).is_symlink():
        raise FileExistsError(
            f"{path} is a symbolic link; cpg-actor writes its own file there, never through a "
            "link: remove the link (what it points to is left as it is)"
        )


def refuse_linked_folders(*folders: Path) -> None:
    """FileExistsError (one line) for the first of ``folders``, where the project writes its
    outputs, that is a symbolic link: it writes into folders of its own, never through a link
    into another folder (perhaps a user's). A path through a link above them is the user's
    choice and is followed."""
    for folder in folders:
        if Path(folder).is_symlink():
            raise FileExistsError(
                f"{folder} is a symbolic link; cpg-actor writes its outputs into a folder of its "
                "own, never through a link: remove the link (what it points to is left as it is)"
            )


def open_own(path: Path, mode: str) -> IO:
    """``open(path, mode)`` for a file the project writes in place (appends to, locks),
    refusing a symbolic link there (:func:`refuse_link`) rather than following it."""
    try:
        return open(path, mode, opener=_no_follow)
    except OSError as error:
        if error.errno == errno.ELOOP:
            refuse_link(path)
        raise


def atomic_write(path: Path, write: Callable[[IO[bytes]], None], fsync: bool = False) -> None:
    """``write(file)`` into a temporary file next to ``path`` (flushed, fsync'ed if asked),
    then renamed over ``path``: ``path`` is replaced whole or not at all, and the temporary
    file is removed if anything fails. A failed write raises its OSError, naming ``path``."""
    path = Path(path)
    tmp = temporary_path(path)
    with naming(path):
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            with open(new_temporary(path), "wb", opener=_no_follow) as f:
                writes = _Writes(f)
                try:
                    write(writes)  # type: ignore[arg-type]
                except Exception:
                    if writes.error is not None:
                        raise writes.error from None
                    raise
                f.flush()
                if fsync:
                    os.fsync(f.fileno())
            os.replace(tmp, path)
        finally:
            tmp.unlink(missing_ok=True)


def atomic_write_text(text: str, path: Path) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically (see :func:`atomic_write`)."""
    atomic_write(Path(path), lambda f: f.write(text.encode("utf-8")))


def describe_os_error(error: OSError) -> str:
    """One line for a file-system error: what failed and on which file."""
    where = f" while writing {error.filename}" if error.filename else ""
    if error.errno == errno.ENOSPC:
        return f"no space left on device{where}"
    if error.errno == errno.EDQUOT:
        return f"disk quota exceeded{where}"
    if error.errno == errno.ENAMETOOLONG:
        return f"file name too long{f': {error.filename}' if error.filename else ''}"
    return str(error)


# -- path limits --------------------------------------------------------------------------------
def check_path_given(value: str | None, flag: str) -> None:
    """ValueError (one line) for a path option given as an empty string: it would name the
    current directory, or silently stand for the option's default."""
    if value is not None and not str(value).strip():
        raise ValueError(f"{flag} is empty; give a path, or leave the option out for its default")


# the longest name `train` writes under its run directory, a TensorBoard event file:
# "tensorboard/events.out.tfevents.<10-digit time>.<host>.<pid>.<n>" (host added by the caller)
_LONGEST_RUN_NAME = len("tensorboard/events.out.tfevents.1234567890..4194304.99")


def check_directory_path(directory: Path, what: str) -> None:
    """NotADirectoryError, before anything starts, for a ``directory`` (``what``: how the
    user gave it) that is a file or a path through one."""
    for path in (directory, *directory.parents):
        if path.exists() and not path.is_dir():
            where = "is a file" if path == directory else f"is inside {path}, a file"
            raise NotADirectoryError(
                f"{what} {directory} {where}, not a directory; give a directory path"
            )


def check_run_dir_length(run_dir: Path) -> None:
    """ValueError if the files ``train`` writes in ``run_dir`` would pass the file system's
    limits on a path (PATH_MAX) or a name (NAME_MAX), so nothing starts that cannot finish."""
    import socket

    absolute = Path(os.path.abspath(run_dir))
    existing = next(p for p in (absolute, *absolute.parents) if p.exists())
    try:
        path_max = os.pathconf(existing, "PC_PATH_MAX")
        name_max = os.pathconf(existing, "PC_NAME_MAX")
    except (OSError, ValueError):
        path_max, name_max = 4096, 255
    for part in absolute.parts[1:]:
        if len(os.fsencode(part)) > name_max:
            raise ValueError(
                f"run directory {run_dir}: the name {part[:40]}... has {len(os.fsencode(part))} "
                f"bytes, above this file system's limit of {name_max}; choose a shorter --run-dir"
            )
    longest = len(os.fsencode(str(absolute))) + 1 + _LONGEST_RUN_NAME
    longest += len(os.fsencode(socket.gethostname()))
    if longest >= path_max:
        raise ValueError(
            f"run directory {str(run_dir)[:60]}... is too long: the files written in it would "
            f"have paths of up to {longest} bytes, above this file system's limit of "
            f"{path_max - 1}; choose a --run-dir shorter by {longest - path_max + 1} characters"
        )


# -- the marker and --overwrite ------------------------------------------------------------------
def write_marker(directory: Path, kind: str) -> None:
    """Mark ``directory`` as made by the project, of ``kind`` (RUN or RESULTS)."""
    data = {"format": MARKER_FORMAT, "kind": kind}
    atomic_write_text(json.dumps(data) + "\n", Path(directory) / MARKER)


def marker_kind(directory: Path) -> str | None:
    """The kind ``directory``'s marker names; None without a readable marker."""
    path = Path(directory) / MARKER
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("format") != MARKER_FORMAT:
        return None
    return data.get("kind")


def _entries(directory: Path, kind: str, prefix: str = "") -> tuple[list[Path], list[Path]]:
    """``(ours, foreign)``: the files and folders under ``directory`` the project writes in a
    directory of ``kind`` (folders after their contents), and everything else. A link is
    always foreign (the project makes none); a project directory inside (a results
    directory's runs, a sweep's settings) is checked as its own kind."""
    files, folders = KINDS[kind]
    nested, nested_kind = _NESTED.get(kind, (None, None))
    ours: list[Path] = []
    foreign: list[Path] = []
    for path in sorted(directory.iterdir()):
        relative = prefix + path.name
        if path.is_symlink():
            foreign.append(path)
        elif path.is_dir():
            if nested is not None and nested.fullmatch(relative):
                if marker_kind(path) != nested_kind:
                    foreign.append(path)
                    continue
                inner_ours, inner_foreign = _entries(path, nested_kind)
                ours += inner_ours + [path]
                foreign += inner_foreign
            elif folders.fullmatch(relative):
                inner_ours, inner_foreign = _entries(path, kind, relative + "/")
                ours += inner_ours + [path]
                foreign += inner_foreign
            else:
                foreign.append(path)
        elif path.is_file() and files.fullmatch(relative):
            ours.append(path)
        else:
            foreign.append(path)
    return ours, foreign


def check_overwritable(directory: Path, kind: str, flag: str = "--overwrite") -> None:
    """FileExistsError (one line, saying what to do) unless ``--overwrite`` may clear the
    existing, non-empty ``directory``: it carries the marker of ``kind`` and holds only files
    the project writes there."""
    directory = Path(directory)
    name = _NAMES[kind]
    found = marker_kind(directory)
    if found != kind:
        if found is not None:
            why = f"it is a {_NAMES.get(found, found)}, not a {name}; choose another directory"
        elif (directory / _SETTINGS[kind]).is_file():
            why = (
                f"it has no {MARKER} marker, so it may be a folder of yours (or a {name} made "
                "before cpg-actor marked its directories); if nothing in it is yours, delete "
                "it yourself, or choose another directory"
            )
        else:
            why = f"it was not made by {_MADE_BY[kind]} (no {MARKER}); choose another directory"
        raise FileExistsError(f"{flag}: refusing to delete anything in {directory}: {why}")
    _, foreign = _entries(directory, kind)
    if foreign:
        shown = ", ".join(str(path.relative_to(directory)) for path in foreign[:5])
        more = f" and {len(foreign) - 5} more" if len(foreign) > 5 else ""
        raise FileExistsError(
            f"{flag}: refusing to delete anything in {directory}: it holds files cpg-actor did "
            f"not write ({shown}{more}); move them out, or choose another directory"
        )


def clear_project_dir(directory: Path, kind: str, keep: tuple[str, ...] = ()) -> None:
    """Delete what the project wrote in ``directory`` (see :func:`check_overwritable`, which
    this calls first), except the top-level names in ``keep``; the directory itself stays."""
    directory = Path(directory)
    check_overwritable(directory, kind)
    ours, _ = _entries(directory, kind)
    for path in ours:
        if path.parent == directory and path.name in keep:
            continue
        if path.is_dir():
            path.rmdir()  # its contents are gone: they came before it
        else:
            path.unlink()


def remove_stale_temporaries(run_dir: Path) -> list[Path]:
    """Remove the temporary files of writes `train` left unfinished (a killed process) in
    ``run_dir`` and its ``checkpoints``; the caller holds the run's lock. Returns them."""
    removed = []
    for folder, names in ((Path(run_dir), _TRAIN_WRITES),
                          (Path(run_dir) / "checkpoints", _CHECKPOINT_WRITES)):  # fmt: skip
        if not folder.is_dir():
            continue
        for path in folder.iterdir():
            match = TEMPORARY.match(path.name)
            if match and names.fullmatch(match["name"]) and path.is_file():
                if not path.is_symlink():
                    path.unlink()
                    removed.append(path)
    return removed
