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


def test_the_two_oscillators_lines_stay_distinguishable_where_they_coincide():
    """Open loop the HFE and KFE phase velocities are equal: the two lines differ in style
    and width (the KFE's dashed over the HFE's), the panel says they overlap; the legends sit
    outside the axes."""
    import numpy as np

    from cpg_actor.robots.hopper.commands.cpg_demo import demo_figure
    from cpg_actor.robots.hopper.cpg import hopper_cpg

    values = {k: v.detach().numpy() for k, v in hopper_cpg(0.01).parametrisation.values().items()}
    t = 0.01 * np.arange(1, 101)
    x = np.stack([0.15 * np.cos(4 * np.pi * t), 0.3 * np.cos(4 * np.pi * t + np.pi)], axis=1)
    same = np.full((100, 2), 4 * np.pi)
    fig = demo_figure(t, x, same, np.zeros((100, 2)), values, 0.01, (0.0, np.pi), [0.0, 0.0],
                      [0.0, 0.0])  # fmt: skip
    hfe, kfe = fig.axes[1].get_lines()[:2]
    assert (hfe.get_label(), kfe.get_label()) == ("HFE", "KFE")
    assert hfe.get_linestyle() != kfe.get_linestyle()
    assert hfe.get_linewidth() > kfe.get_linewidth()  # the wider one shows around the other
    assert "overlap" in fig.axes[1].get_title(loc="left")
    assert [axis.get_ylabel().split("\n")[0] for axis in fig.axes] == [
        "output $x$: offset from", "phase velocity", "amplitude acceleration"]  # fmt: skip
    for axis in fig.axes:
        assert axis.get_legend().get_bbox_to_anchor().x0 > axis.bbox.x1

    apart = same + np.array([1.0, -1.0])  # with feedback they differ: nothing to say
    fig = demo_figure(t, x, apart, np.zeros((100, 2)), values, 0.01, (0.0, np.pi), [1.0, -1.0],
                      [0.0, 0.0])  # fmt: skip
    assert fig.axes[1].get_title(loc="left") == ""
