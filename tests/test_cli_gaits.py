"""`cpg-actor gaits`: the quadruped's open-loop gait presets, their diagram and summary."""

import json

import numpy as np
import pytest

from cpg_actor.cli import main
from cpg_actor.commands.gaits import touchdown_phases


def test_touchdown_phases_of_a_synthetic_trot():
    """Feet on the ground half of each 0.5 s cycle; RF and LH land half a cycle after LF."""
    dt, steps = 0.02, 200
    t = np.arange(steps) * dt
    lf = (t % 0.5) < 0.25
    late = ((t - 0.25) % 0.5) < 0.25
    contact = np.stack([lf, late, late, lf], axis=1)
    # within a control step (0.04 of a cycle): the trace is sampled at 50 Hz
    assert touchdown_phases(contact, dt, frequency=2.0) == pytest.approx([0, 0.5, 0.5, 0], abs=0.04)
    assert np.isnan(touchdown_phases(np.ones((steps, 4), dtype=bool), dt, 2.0)).all()


def test_gaits_writes_its_diagram_and_summary_and_keeps_existing_files(tmp_path, capsys):
    out = tmp_path / "gaits"
    args = ["gaits", "--gaits", "trot", "pronk", "--seconds", "2", "--robots", "2",
            "--out", str(out)]  # fmt: skip
    assert main(args) == 0
    summary = json.loads((out / "gaits.json").read_text())
    assert set(summary["gaits"]) == {"trot", "pronk"}
    trot = summary["gaits"]["trot"]
    assert trot["fell"] == 0 and trot["robots"] == 2
    assert set(trot["duty_factor"]) == {"LF", "RF", "LH", "RH"}
    assert (out / "gaits.png").stat().st_size > 10_000
    capsys.readouterr()
    assert main(args) == 2  # refuses to replace them
    assert "--overwrite" in capsys.readouterr().err
    assert main([*args, "--overwrite"]) == 0
    assert main(["gaits", "--seconds", "-1", "--out", str(tmp_path / "x")]) == 2


def test_the_leg_layout_trots_forward_faster_with_the_drive(tmp_path):
    """`--layout leg` (one oscillator per leg, foot-space pattern), the trot open loop, 8 robots
    for 20 s: none falls; the feet land as a trot (the diagonal pairs half a cycle apart, within
    0.15 of a cycle); the robots walk forward, faster at a 1 m/s command than at 0 (0.06 to
    0.61 m/s measured)."""
    speeds = {}
    for command in (0.0, 1.0):
        out = tmp_path / f"c{command}"
        args = ["gaits", "--layout", "leg", "--gaits", "trot", "--robots", "8",
                "--command", str(command), "--out", str(out)]  # fmt: skip
        assert main(args) == 0
        summary = json.loads((out / "gaits.json").read_text())
        assert summary["layout"] == "leg"
        trot = summary["gaits"]["trot"]
        assert trot["fell"] == 0
        speeds[command] = trot["forward_speed"]
        if command == 0.0:  # at 1 m/s the longer steps let the pairs drift (RF 0.34 there)
            phases = [trot["touchdown_phase"][leg] for leg in ("RF", "LH", "RH")]
            trot_table = (0.5, 0.5, 0.0)
            distance = [min(abs(p - t), 1 - abs(p - t))
                        for p, t in zip(phases, trot_table, strict=True)]  # fmt: skip
            assert max(distance) < 0.15, phases
    assert speeds[1.0] > 0.4 and speeds[1.0] > speeds[0.0] + 0.3
