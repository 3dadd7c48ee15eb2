"""cpg_actor.inputs: a user's file read with one-line errors naming it (a missing file, bytes
not text, text not JSON or YAML, a damaged archive, a missing key), for the command line and
the results folders' analyses."""

import gzip
import math

import numpy as np
import pytest

from cpg_actor.inputs import (
    InputError,
    MissingKey,
    load_npz,
    read_json,
    read_jsonl,
    read_yaml,
    run_script,
)


def test_a_missing_key_names_the_file_and_is_still_a_key_error(tmp_path):
    path = tmp_path / "grid.json"
    path.write_text('{"means": {"flat": {"fell": null}}, "rows": []}')
    grid = read_json(path, nulls_as_nan=True)
    assert math.isnan(grid["means"]["flat"]["fell"]) and grid.get("other") is None
    with pytest.raises(MissingKey, match=r"grid.json: no 'ground' where it is read \(has: fell"):
        grid["means"]["flat"]["ground"]
    with pytest.raises(KeyError):  # code that expects a KeyError still gets one
        grid["missing"]
    assert str(MissingKey("one line")) == "one line"


@pytest.mark.parametrize(
    ("name", "data", "message"),
    [
        ("a.json", None, "a.json does not exist"),
        ("a.json", b"\xff", "a.json is not text (byte 0 is not UTF-8)"),
        ("a.json", b'{"a": 1,}', "a.json is not JSON (line 1, column 9"),
        ("a.json", b"[]", "a.json holds a list, not the JSON an object expected"),
        ("a.json.gz", gzip.compress(b"{}" * 50)[:15], "a.json.gz is not a whole gzip file"),
    ],
)
def test_a_damaged_json_file_is_one_line_naming_it(tmp_path, name, data, message):
    path = tmp_path / name
    if data is not None:
        path.write_bytes(data)
    with pytest.raises(InputError) as error:
        read_json(path, "a benchmark's JSON")
    text = str(error.value)
    assert message in text and "\n" not in text and "a benchmark's JSON" in text
    path.unlink(missing_ok=True)
    packed = tmp_path / "b.json.gz"
    packed.write_bytes(gzip.compress(b'{"a": 1}'))
    assert read_json(packed) == {"a": 1}


def test_metrics_lines_a_cut_last_line_is_left_out_a_damaged_one_named(tmp_path):
    path = tmp_path / "metrics.jsonl"
    path.write_text('{"global_step": 1}\n\n{"global_step": 2}\n{"global_st')
    assert [row["global_step"] for row in read_jsonl(path)] == [1, 2]
    path.write_text('{"global_step": 1}\n{"global_st\n{"global_step": 2}\n')
    with pytest.raises(InputError, match=r"metrics.jsonl, line 2: not JSON"):
        read_jsonl(path)
    path.write_text('{"global_step": 1}\nnull\n')
    with pytest.raises(InputError, match=r"metrics.jsonl, line 2: not a JSON object"):
        read_jsonl(path)


def test_a_damaged_npz_or_yaml_is_one_line(tmp_path):
    path = tmp_path / "traces.npz"
    np.savez(path, episode_return=np.arange(3.0))
    assert load_npz(path)["episode_return"].tolist() == [0.0, 1.0, 2.0]
    path.write_bytes(path.read_bytes()[:40])
    with pytest.raises(InputError, match=r"traces.npz is not a whole .npz file"):
        load_npz(path)
    settings = tmp_path / "reproduce.yaml"
    settings.write_text("settings: [\n")
    with pytest.raises(InputError, match=r"reproduce.yaml is not valid YAML"):
        read_yaml(settings)


def test_a_script_run_through_run_script_ends_in_one_line(tmp_path, capsys):
    def damaged():
        read_json(tmp_path / "missing.json")

    def wrong_shape():
        rows: object = [1]  # a list where a mapping is read
        return rows["key"]

    assert run_script(damaged, "analysis.py") == 2
    assert capsys.readouterr().err.startswith("analysis.py: error: ")
    assert run_script(wrong_shape, "analysis.py") == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "(TypeError: list indices" in err
    assert run_script(lambda: None, "analysis.py") == 0
