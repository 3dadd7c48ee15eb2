"""`cpg-actor gaits`: the quadruped's open-loop gait presets, their diagram and summary."""

import json

import numpy as np
import pytest

from cpg_actor.cli import main
from cpg_actor.commands.gaits import touchdown_phases
from cpg_actor.robots.registry import ROBOTS


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


def test_gaits_runs_any_robot_with_gait_presets_and_refuses_one_without(tmp_path, capsys):
    """The Go1 through the registry: its legs, its gaits' footfalls; the hopper's CPG has no
    gaits: a one-line error naming the robots that have them."""
    out = tmp_path / "go1"
    args = ["gaits", "--robot", "go1", "--gaits", "walk", "--seconds", "1", "--robots", "1",
            "--out", str(out)]  # fmt: skip
    assert main(args) == 0
    summary = json.loads((out / "gaits.json").read_text())
    assert summary["robot"] == "go1" and summary["layout"] == "joint"
    assert list(summary["gaits"]["walk"]["duty_factor"]) == ["FR", "FL", "RR", "RL"]
    capsys.readouterr()
    assert main(["gaits", "--robot", "hopper", "--out", str(tmp_path / "h")]) == 2
    err = capsys.readouterr().err.strip()
    gaited = [name for name, robot in ROBOTS.items()
              if any(layout.gaits for layout in robot.cpg_layouts().values())]  # fmt: skip
    assert {"anymal", "go1"} <= set(gaited) and "hopper" not in gaited
    assert f"hopper: its CPG has no gait presets (robots with gaits: {', '.join(gaited)})" in err
    assert len(err.splitlines()) == 1
    assert main(["gaits", "--robot", "go1", "--gaits", "gallop", "--out", str(tmp_path)]) == 2
    assert "the go1's joint layout has the gaits trot, pace" in capsys.readouterr().err


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


def test_the_gait_figure_draws_each_gaits_reference_next_to_the_cpgs_result():
    """Next to each gait's diagram, one cycle of its reference pattern (grey: each leg's
    touchdown at the gait's phase offset) over the CPG's measured one (blue)."""
    from cpg_actor.commands.gaits import REFERENCE_DUTY, gaits_figure
    from cpg_actor.robots.anymal.gaits import ANYMAL_GAITS
    from cpg_actor.robots.common.quadruped.gaits import GAITS

    contact = np.zeros((100, 4), dtype=bool)
    contact[::2] = True
    summary = {
        gait: {"fell": 0, "robots": 1, "forward_speed": 0.2,
               "duty_factor": dict.fromkeys(("LF", "RF", "LH", "RH"), 0.6),
               "touchdown_phase": {"LF": 0.0, "RF": 0.5, "LH": 0.5, "RH": float("nan")}}
        for gait in ("trot", "walk")
    }  # fmt: skip
    traces = {"trot": (contact, 0.02), "walk": (contact, 0.02)}
    fig = gaits_figure(traces, summary, 0.5, ANYMAL_GAITS.legs, ANYMAL_GAITS.footfalls())
    diagrams, references = fig.axes[0::2], fig.axes[1::2]
    assert [axis.get_title(loc="left").split(":")[0] for axis in diagrams] == ["trot", "walk"]
    for gait, axis in zip(("trot", "walk"), references, strict=True):
        assert f"{gait} reference" in axis.get_title(loc="left")
        labels = [c.get_label() for c in axis.collections]
        assert labels.count(f"reference {gait}") == 1 and labels.count("CPG (robot 0)") == 1
        grey = axis.collections[labels.index(f"reference {gait}")].get_facecolor()[0]
        # each leg's reference bar: from its phase offset (a wrapped bar also starts at 0)
        starts: dict[str, set[float]] = {}
        for collection in axis.collections:
            if not np.allclose(collection.get_facecolor()[0], grey):
                continue
            for path in collection.get_paths():
                leg = ("RH", "LH", "RF", "LF")[int(round(path.vertices[:, 1].mean() - 0.21))]
                starts.setdefault(leg, set()).add(round(float(path.vertices[:, 0].min()), 6))
        for leg, offset in zip(("LF", "RF", "LH", "RH"), GAITS[gait], strict=True):
            assert offset in starts[leg], (gait, leg, starts)
            assert starts[leg] <= {offset, 0.0}
        assert axis.get_xlim() == (0.0, 1.0)
    assert f"{REFERENCE_DUTY:g} of a cycle" in references[-1].get_xlabel()
