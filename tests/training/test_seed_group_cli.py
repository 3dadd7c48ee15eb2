"""`cpg-actor train --seeds K`: K seeds in one process, each a run directory of its own."""

import pytest
import torch

from cpg_actor.cli import main
from cpg_actor.config import TrainConfig

# 2 envs x 8 steps per iteration, eager, a checkpoint every iteration
TINY = ["--set", "ppo.compile=false", "--num-envs", "2", "--set", "ppo.num_steps=8",
        "--set", "ppo.num_minibatches=2", "--set", "ppo.num_epochs=1", "--set",
        "checkpoint_interval=1", "--set", "eval_interval=0", "--no-progress"]  # fmt: skip


def test_a_group_trains_each_seed_into_a_run_of_its_own_that_resumes_alone(tmp_path, capsys):
    group = tmp_path / "group"
    argv = ["train", "--seeds", "2", "--seed", "3", "--total-steps", "32", "--run-dir",
            str(group), *TINY]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "2 seeds (3-4) in one process" in out
    assert "seed 3: done: 32 steps" in out and "seed 4: done: 32 steps" in out
    weights = []
    for seed in (3, 4):
        run_dir = group / f"seed-{seed}"
        assert TrainConfig.load(run_dir / "config.yaml").seed == seed
        state = torch.load(run_dir / "checkpoints" / "last.pt", weights_only=True)
        assert state["iteration"] == 2
        weights.append(torch.cat([v.flatten() for v in state["agent_state"].values()]))
    assert not torch.equal(weights[0], weights[1])  # each seed its own run
    # a seed's run continues as a run of its own
    resume = ["train", "--resume", "--run-dir", str(group / "seed-3"), "--total-steps", "48",
              "--no-progress"]  # fmt: skip
    assert main(resume) == 0
    assert "done: 48 steps" in capsys.readouterr().out


def test_a_group_never_overwrites_a_run_without_overwrite(tmp_path, capsys):
    group = tmp_path / "group"
    (group / "seed-1").mkdir(parents=True)
    (group / "seed-1" / "notes.txt").write_text("keep")
    argv = ["train", "--seeds", "2", "--total-steps", "16", "--run-dir", str(group), *TINY]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "seed-1 already exists; pass --overwrite" in err and "--resume --run-dir" in err
    assert main([*argv, "--overwrite"]) == 2  # not the project's: refused, kept
    assert "refusing to delete" in capsys.readouterr().err
    assert (group / "seed-1" / "notes.txt").read_text() == "keep"
    assert not (group / "seed-0").exists()


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--seeds", "0"], "--seeds must be an integer from 1 to 10,000, got 0"),
        (["--seeds", "2", "--resume"], "a seed of a group resumes as a run of its own"),
        (["--seeds", "2", "--agent", "mlp-warm"], "starts with a warm start"),
        (["--seeds", "2", "--agent", "open-loop-es"], "searched by CMA-ES"),
    ],
)
def test_what_a_group_cannot_train_is_one_line(tmp_path, capsys, argv, message):
    run_dir = tmp_path / "group"
    assert main(["train", "--run-dir", str(run_dir), "--total-steps", "16", *argv, *TINY]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not run_dir.exists()
