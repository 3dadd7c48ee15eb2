"""`cpg-actor curves`: several runs' learning curves in one figure, grouped by agent, budget
and settings, with the last logged values per run and per group; a mean only over runs that
trained alike and where all of them have data; clear errors; the figure never in the working
directory unless asked, nothing overwritten unless asked."""

import json
import math

import pytest

from cpg_actor import plots
from cpg_actor.cli import main
from cpg_actor.config import TrainConfig, apply_dict


def fake_run(path, agent, values, metric="eval/speed_error", every=1000, **config):
    path.mkdir(parents=True)
    train_config = TrainConfig(agent=agent)
    apply_dict(train_config, config, "")
    train_config.save(path / "config.yaml")
    rows = [{"global_step": every * (i + 1), metric: v, "charts/SPS": 1.0}
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
    assert summary["groups"]["mlp"]["runs"] == runs[:2]
    mlp = summary["groups"]["mlp"]["metrics"]["eval/speed_error"]
    assert mlp["runs"] == 2 and abs(mlp["mean"] - 0.1) < 1e-9 and abs(mlp["std"] - 0.05) < 1e-9
    # a NaN is not a value: the cpg-actor run's last logged one is 0.4, at 2,000 steps
    assert summary["runs"][runs[2]]["eval/speed_error"] == {"step": 2000, "value": 0.4}
    assert "mlp: last logged eval/speed_error 0.1 +- 0.05 (2 runs)" in capsys.readouterr().out
    assert main(args) == 2  # kept
    assert "curves.png exists; pass --overwrite" in capsys.readouterr().err
    assert main([*args, "--overwrite"]) == 0
    assert main([*args, "--overwrite", "--group-by", "run"]) == 0
    assert set(json.loads(out.with_suffix(".json").read_text())["groups"]) == {"m0", "m1", "c0"}
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


def test_a_typo_in_the_metric_is_named_with_the_logged_ones_even_if_the_figure_exists(
    tmp_path, capsys
):
    run = fake_run(tmp_path / "m0", "mlp", [0.6])
    assert main(["curves", run, "--metric", "eval/speed_error"]) == 0
    assert main(["curves", run, "--metric", "eval/sped_error"]) == 2
    err = capsys.readouterr().err
    assert "no run logged 'eval/sped_error'; the runs logged: charts/SPS, eval/speed_error" in err
    assert main(["curves", run, "--out", str(tmp_path / "x.pdf")]) == 2
    assert "--out must end in .png" in capsys.readouterr().err


def drawn_figure(monkeypatch):
    """The figure `curves` saves, kept for the test to read."""
    figures = []
    save = plots.save_figure
    monkeypatch.setattr(
        plots, "save_figure", lambda fig, path: figures.append(fig) or save(fig, path)
    )
    return figures


def test_runs_of_different_budgets_or_settings_are_never_averaged(tmp_path, capsys, monkeypatch):
    """Two 500k runs (seeds 0 and 1, one on another device: the same training) are one group,
    their mean drawn where both have data, with a band; a 30k run and a run with another
    learning rate are groups of their own, one line each, no band; legends say which."""
    figures = drawn_figure(monkeypatch)
    runs = [
        fake_run(tmp_path / "a0", "mlp", [1.0, 2.0, 3.0], every=100_000, seed=0),
        fake_run(tmp_path / "a1", "mlp", [3.0, 4.0], every=100_000, seed=1, device="cuda"),
        fake_run(tmp_path / "short", "mlp", [5.0, 6.0], every=10_000, total_steps=30_000),
        fake_run(tmp_path / "lr", "mlp", [7.0], every=100_000, ppo={"learning_rate": 1e-3}),
    ]  # fmt: skip
    assert main(["curves", *runs, "--metric", "eval/speed_error"]) == 0
    (axis,) = figures[0].axes
    legend = [text.get_text() for text in axis.get_legend().get_texts()]
    assert legend == [
        "mlp, 500k steps, mean of 2 runs ± 95% CI",
        "mlp, 30k steps, 1 run",
        "mlp, 500k steps, ppo.learning_rate=0.001, 1 run",
    ]
    mean = next(line for line in axis.get_lines() if line.get_label() == legend[0])
    assert list(mean.get_xdata()) == [100, 200]  # thousands; 300k: only one run has data
    assert list(mean.get_ydata()) == [2.0, 3.0]
    assert len(axis.collections) == 1  # the one band: the group of two runs
    band = axis.collections[0].get_paths()[0].vertices[:, 1]
    # std of (1, 3) and (2, 4): sqrt(2); Student t's 0.975 quantile with 1 degree of freedom
    half = 12.7062047 * math.sqrt(2.0) / math.sqrt(2)
    assert min(band) == pytest.approx(2.0 - half) and max(band) == pytest.approx(3.0 + half)
    assert axis.get_xlabel() == "training steps (thousands)"
    summary = json.loads((tmp_path / "a0" / "curves.json").read_text())
    assert summary["groups"]["mlp, 500k steps"]["runs"] == runs[:2]
    assert summary["groups"]["mlp, 30k steps"]["total_steps"] == 30_000
    assert "mlp, 30k steps: last logged eval/speed_error 6 +- 0 (1 run)" in capsys.readouterr().out


def test_the_figure_goes_beside_the_runs_never_into_the_working_directory(
    tmp_path, capsys, monkeypatch
):
    run = fake_run(tmp_path / "runs" / "m0", "mlp", [0.6, 0.2])
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    assert main(["curves", run, "--metric", "eval/speed_error"]) == 0
    assert list(cwd.iterdir()) == []
    out = tmp_path / "runs" / "m0" / "curves.png"
    assert out.is_file() and out.with_suffix(".json").is_file()
    assert f"figure {out}; summary {out.with_suffix('.json')}" in capsys.readouterr().out
    before = out.read_bytes()
    assert main(["curves", run, "--metric", "eval/speed_error", "--title", "x"]) == 2
    assert "curves.png exists; pass --overwrite" in capsys.readouterr().err
    assert out.read_bytes() == before
    assert main(["curves", run, "--metric", "eval/speed_error", "--overwrite"]) == 0


def test_steps_axes_are_in_units_the_budget_reads_in():
    assert plots.step_axis(8_192) == (1e3, "training steps (thousands)")
    assert plots.step_axis(20e6, "time steps") == (1e6, "time steps (millions)")
    assert plots.step_axis(512) == (1.0, "training steps")
    assert [plots.steps_text(n) for n in (500_000, 20_000_000, 8_192, 512)] == [
        "500k", "20M", "8.19k", "512"]  # fmt: skip
