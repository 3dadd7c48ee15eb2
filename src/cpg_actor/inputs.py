"""Reading files the user gives (a run's ``metrics.jsonl``, a study's results) with one-line
errors: each reader raises :class:`InputError` naming the file and what is wrong with it (a
missing file, bytes that are not text, text that is not JSON, a damaged archive, a missing
key). ``InputError`` is a ValueError, which ``cpg-actor`` reports in one line; the analysis
scripts of ``docs/results`` run their ``main`` through :func:`run_script`, which does the same.

A JSON object read here is a :class:`Record`: looking up a key it lacks raises
:class:`MissingKey` (an InputError, and a KeyError for code that expects one) naming the file.
"""

from __future__ import annotations

import gzip
import json
import math
import sys
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any


class InputError(ValueError):
    """A file the user gave is missing, damaged or not the one expected (one line)."""


class MissingKey(InputError, KeyError):
    """A JSON object read from a file lacks a key the reader needs."""

    def __str__(self) -> str:  # KeyError's would quote the whole message
        return str(self.args[0])


class Record(dict):
    """A JSON object read from ``source``; a missing key raises :class:`MissingKey`."""

    source = "a file"

    def __missing__(self, key: Any) -> Any:
        keys = [str(k) for k in self][:8]
        has = ", ".join(keys) + (", ..." if len(self) > len(keys) else "")
        raise MissingKey(f"{self.source}: no {key!r} where it is read (has: "
                         f"{has or 'nothing'}); not the file expected, or damaged")  # fmt: skip


def _records(source: Path, nulls_as_nan: bool) -> Callable[[dict], Record]:
    """A json ``object_hook`` making each object a :class:`Record` of ``source``."""

    def hook(mapping: dict) -> Record:
        record = Record(mapping if not nulls_as_nan else
                        {k: math.nan if v is None else v for k, v in mapping.items()})  # fmt: skip
        record.source = str(source)
        return record

    return hook


def read_text(path: Path, what: str = "") -> str:
    """The UTF-8 text of ``path`` (gzip-decompressed where its name ends in ``.gz``);
    ``what``: what the file should be, for the message (e.g. "cpg-actor eval --grid's
    output")."""
    path = Path(path)
    hint = f" ({what})" if what else ""
    if not path.is_file():
        kind = "is a folder" if path.is_dir() else "does not exist"
        raise InputError(f"{path} {kind}; a file is needed{hint}")
    try:
        data = path.read_bytes()
        if path.name.endswith(".gz"):
            data = gzip.decompress(data)
        return data.decode("utf-8")
    except (EOFError, zlib.error, gzip.BadGzipFile) as error:
        raise InputError(f"{path} is not a whole gzip file ({error}){hint}") from None
    except UnicodeDecodeError as error:
        raise InputError(f"{path} is not text (byte {error.start} is not UTF-8){hint}") from None


def parse_json(text: str, source: Path | str, what: str = "", nulls_as_nan: bool = False) -> Any:
    """``text`` (from ``source``) as JSON, its objects :class:`Record` s; ``nulls_as_nan``:
    each null (an undefined number, as ``cpg_actor.robustness.protocol.json_text`` writes it)
    read as NaN."""
    try:
        return json.loads(text, object_hook=_records(Path(source), nulls_as_nan))
    except json.JSONDecodeError as error:
        hint = f" ({what})" if what else ""
        raise InputError(f"{source} is not JSON (line {error.lineno}, column {error.colno}: "
                         f"{error.msg}){hint}") from None  # fmt: skip


def read_json(path: Path, what: str = "", kind: type | None = dict,
              nulls_as_nan: bool = False) -> Any:  # fmt: skip
    """The JSON in ``path`` (``.gz``: compressed), its objects :class:`Record` s; ``kind``:
    the type its top level must have (None: any)."""
    data = parse_json(read_text(path, what), path, what, nulls_as_nan)
    if kind is not None and not isinstance(data, kind):
        names = {dict: "an object", list: "a list", str: "a string"}
        found = next((names[k] for k in names if isinstance(data, k)), type(data).__name__)
        raise InputError(f"{path} holds {found}, not the JSON {names.get(kind, kind.__name__)} "
                         "expected" + (f" ({what})" if what else ""))  # fmt: skip
    return data


def read_jsonl(path: Path, what: str = "") -> list[Record]:
    """The rows of a JSON-lines file (``metrics.jsonl``), each a JSON object; a last line
    without its end (a run cut off while writing it) is left out, any other damaged line is
    an :class:`InputError` naming its number."""
    text = read_text(path, what)
    lines = text.splitlines()
    rows: list[Record] = []
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            row = json.loads(line, object_hook=_records(Path(path), False))
        except json.JSONDecodeError as error:
            if number == len(lines) and not text.endswith("\n"):
                break  # cut short mid-write: the rows before it stand
            raise InputError(f"{path}, line {number}: not JSON ({error.msg}); the file is "
                             "damaged" + (f" ({what})" if what else "")) from None  # fmt: skip
        if not isinstance(row, dict):
            raise InputError(f"{path}, line {number}: not a JSON object of named values; "
                             "the file is damaged")  # fmt: skip
        rows.append(row)
    return rows


def read_yaml(path: Path, what: str = "") -> Any:
    """The YAML in ``path``, read within the bounds of :mod:`cpg_actor.safe_yaml`."""
    from cpg_actor.safe_yaml import read_yaml as read_bounded

    path = Path(path)
    if not path.is_file():  # the same line as the other readers
        kind = "is a folder" if path.is_dir() else "does not exist"
        raise InputError(f"{path} {kind}; a file is needed{f' ({what})' if what else ''}")
    try:
        return read_bounded(path)
    except ValueError as error:
        raise InputError(str(error)) from None


def load_npz(path: Path, what: str = "") -> dict[str, Any]:
    """Every array of the ``.npz`` file ``path``, read now (a damaged file fails here)."""
    import zipfile

    import numpy as np

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path} does not exist" + (f" ({what})" if what else ""))
    try:
        with np.load(path, allow_pickle=False) as data:
            return {name: data[name] for name in data.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as error:
        reason = (str(error).strip() or type(error).__name__).splitlines()[0]
        raise InputError(f"{path} is not a whole .npz file ({reason})"
                         + (f" ({what})" if what else "")) from None  # fmt: skip


def run_script(main: Callable[[], Any], name: str) -> int:
    """Run an analysis script's ``main``; a damaged or missing input is one line on stderr
    (``NAME: error: ...``) and exit status 2, never a traceback. An input of the right syntax
    but another shape (a list where a number is read) fails deeper: that too is one line,
    saying the inputs are not the ones the script reads."""
    try:
        main()
    except InputError as error:
        print(f"{name}: error: {error}", file=sys.stderr)
        return 2
    except (KeyError, TypeError, AttributeError, IndexError, ValueError) as error:
        text = (str(error).strip() or type(error).__name__).splitlines()[0]
        print(f"{name}: error: its inputs are not the files it reads, or are damaged "
              f"({type(error).__name__}: {text})", file=sys.stderr)  # fmt: skip
        return 2
    except OSError as error:
        from cpg_actor.files import describe_os_error

        print(f"{name}: error: {describe_os_error(error)}", file=sys.stderr)
        return 1
    return 0
