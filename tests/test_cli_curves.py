"""`cpg-actor curves`: several runs' learning curves in one figure, grouped by agent, with the
last logged values per run and per agent; clear errors; nothing overwritten unless asked."""

import json

from cpg_actor.cli import main
from cpg_actor.config import TrainConfig


def fake_run(path, agent, values, metric="eval/speed_error"):
    path.mkdir(parents=True)
    TrainConfig(agent=agent).save(path / "config.yaml")
    rows = [{"global_step": 1000 * (i + 1), metric: v, "charts/SPS": 1.0}
            for i, v in enumerate(values)]  # fmt: skip
    rows.insert(1, {"global_step": 1500, "charts/SPS": 2.0})  # a row without the metric
    (path / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    return str(path)


def test_curves_groups_runs_by_agent_and_summarises_the_last_values(tmp_path, capsys):
    runs = [fake_run(tmp_path / "m0", "mlp", [0.6, 0.2, 0.05]),
            fake_run(tmp_path / "m1", "mlp", [0.6, 0.3, 0.15]),
            fake_run(tmp_path / "c0", "cpg-actor", [0.5, 0.4, float("nan")])]  # fmt: skip
    out = tmp_path / "fig" / "curves.png"
    args = ["curves", *runs, "--metric", "eval/speed_error", "--out", str(out)]
    assert main(args) == 0
    assert out.stat().st_size > 5000
    summary = json.loads(out.with_suffix(".json").read_text())
    mlp = summary["agents"]["mlp"]["eval/speed_error"]
    assert mlp["runs"] == 2 and abs(mlp["mean"] - 0.1) < 1e-9 and abs(mlp["std"] - 0.05) < 1e-9
    # a NaN is not a value: the cpg-actor run's last logged one is 0.4, at 2,000 steps
    assert summary["runs"][runs[2]]["eval/speed_error"] == {"step": 2000, "value": 0.4}
    assert "mlp: last logged eval/speed_error 0.1 +- 0.05 (2 runs)" in capsys.readouterr().out
    assert main(args) == 2  # kept
    assert "curves.png exists; pass --overwrite" in capsys.readouterr().err
    assert main([*args, "--overwrite"]) == 0
    assert main([*args, "--overwrite", "--group-by", "run"]) == 0
    assert set(json.loads(out.with_suffix(".json").read_text())["agents"]) == {"m0", "m1", "c0"}
    # one budget for runs of different lengths: the rows up to 2k steps
    assert main([*args, "--overwrite", "--max-steps", "2k"]) == 0
    summary = json.loads(out.with_suffix(".json").read_text())
    assert summary["runs"][runs[0]]["eval/speed_error"] == {"step": 2000, "value": 0.2}


def test_curves_says_what_is_wrong(tmp_path, capsys):
    run = fake_run(tmp_path / "m0", "mlp", [0.6])
    assert main(["curves", run, "--metric", "eval/nothing", "--out", str(tmp_path / "x.png")]) == 2
    assert "no run logged 'eval/nothing'" in capsys.readouterr().err
    assert main(["curves", str(tmp_path / "missing"), "--out", str(tmp_path / "x.png")]) == 2
    assert "does not exist; is" in capsys.readouterr().err
    assert main(["curves", run, "--out", str(tmp_path / "x.pdf")]) == 2
    assert "--out must end in .png" in capsys.readouterr().err
