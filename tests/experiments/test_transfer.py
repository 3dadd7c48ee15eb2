"""`cpg-actor transfer`: final policies evaluated in both simulators, and the report's table."""

import json

import numpy as np
import pytest

from cpg_actor.cli import main
from cpg_actor.experiments import metrics as m
from cpg_actor.experiments.transfer import kept, transfer_lines
from tiny import trained_run  # tests/tiny.py (pytest puts tests/ on sys.path)


def test_transfer_evaluates_each_run_in_both_simulators(tmp_path, capsys):
    out = tmp_path / "out"
    for seed in (0, 1):
        run_dir = out / "runs" / "cpg-actor" / f"seed{seed}"
        trained_run(run_dir, "cpg-actor", seed=seed)
    assert main(["transfer", str(out), "--episodes", "2"]) == 0
    data = json.loads((out / "transfer.json").read_text())
    runs = data["runs"]["cpg-actor"]
    assert set(runs) == {"0", "1"}
    for values in runs.values():
        assert values["trained_in"] == "mujoco"
        assert np.isfinite(values["mujoco"]["return"]) and np.isfinite(values["pybullet"]["return"])
    assert "## Cross-simulator transfer" in (out / "report.md").read_text()
    assert main(["transfer", str(out)]) == 2  # refuses to replace transfer.json
    assert "pass --overwrite" in capsys.readouterr().err


def test_kept_share_is_other_over_own_with_a_paired_interval():
    data = {"episodes": 5, "seed": 1000, "runs": {"mlp": {
        str(s): {"trained_in": "mujoco", "mujoco": {"return": 100.0 * (s + 1), "hop_height": 0.3},
                 "pybullet": {"return": 90.0 * (s + 1), "hop_height": 0.15}}
        for s in range(3)}}}  # fmt: skip
    row = kept(data)["mlp"]
    assert row["return_kept"].estimate == pytest.approx(0.9)
    # paired: every seed keeps exactly 90 %, so the interval has no width
    assert row["return_kept"].low == pytest.approx(0.9) == row["return_kept"].high
    assert row["hop_height_kept"].estimate == pytest.approx(0.5)
    assert m.bootstrap_ratio([90.0, 180.0, 270.0], [100.0, 200.0, 300.0]).low < 0.9
    assert "| `mlp` | mujoco | 3 | 200 | 180 | 90% [90, 90] |" in "\n".join(transfer_lines(data))
