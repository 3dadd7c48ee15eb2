"""`cpg-actor cpg-demo` writes a PNG atomically and refuses to overwrite without --overwrite."""

from __future__ import annotations

import os

import pytest

from cpg_actor.cli import main

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _is_png(path) -> bool:
    data = path.read_bytes()
    # signature, then the IHDR chunk, and the IEND chunk at the very end
    return data[:8] == PNG_SIGNATURE and data[12:16] == b"IHDR" and data[-8:-4] == b"IEND"


def test_cpg_demo_writes_a_png_and_refuses_to_overwrite(tmp_path, capsys):
    old_umask = os.umask(0o022)
    try:
        _run_demo(tmp_path, capsys)
    finally:
        os.umask(old_umask)


def _run_demo(tmp_path, capsys):
    out = tmp_path / "figures" / "demo.png"  # the parent folder is created
    argv = ["cpg-demo", "--duration", "1.0", "--dt", "0.01", "--out", str(out)]
    assert main(argv + ["--xi", "0.5", "--kappa", "1.0", "-2.0"]) == 0
    assert out.is_file() and _is_png(out)
    assert f"wrote {out}" in capsys.readouterr().out
    assert [p.name for p in out.parent.iterdir()] == ["demo.png"]  # no temporary file left
    assert out.stat().st_mode & 0o777 == 0o644  # a new file's mode, not mkstemp's 0600
    before = out.read_bytes()
    mtime = out.stat().st_mtime_ns

    assert main(argv) == 2
    assert "exists; pass --overwrite" in capsys.readouterr().err
    assert out.read_bytes() == before and out.stat().st_mtime_ns == mtime

    assert main(argv + ["--overwrite", "--initial-phase", "0", "1"]) == 0
    assert _is_png(out) and out.read_bytes() != before  # different feedback, different figure
    assert [p.name for p in out.parent.iterdir()] == ["demo.png"]


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--dt", "0"], "--dt must be a positive"),
        (["--duration", "-1"], "--duration must be a positive"),
        (["--xi", "1", "2", "3"], "--xi takes one value or one per oscillator"),
        (["--kappa", "nan"], "--kappa must be finite"),
        (["--out", "demo.jpg"], "--out must be a .png"),
        (["--initial-phase", "0", "inf"], "--initial-phase must be finite"),
    ],
)
def test_cpg_demo_rejects_bad_options(tmp_path, capsys, extra, message):
    argv = ["cpg-demo", "--duration", "0.5", "--out", str(tmp_path / "demo.png"), *extra]
    assert main(argv) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "demo.png").exists()
