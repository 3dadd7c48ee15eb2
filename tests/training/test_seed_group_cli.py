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
        (["--seeds", "2", "--resume"], "only --total-steps may change"),
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


def test_overwrite_takes_every_seeds_lock_before_it_deletes_anything(tmp_path, capsys):
    from cpg_actor.training.run_lock import RunLock

    group = tmp_path / "group"
    argv = ["train", "--seeds", "2", "--total-steps", "16", "--run-dir", str(group), *TINY]
    assert main(argv) == 0
    before = {seed: sorted(p.relative_to(group) for p in (group / f"seed-{seed}").rglob("*"))
              for seed in (0, 1)}  # fmt: skip
    capsys.readouterr()
    with RunLock(group / "seed-1"):  # as if another `cpg-actor train` were writing seed 1
        assert main([*argv, "--overwrite"]) == 2
    err = capsys.readouterr().err
    assert "seed-1 is in use by process" in err and len(err.strip().splitlines()) == 1
    for seed in (0, 1):  # seed 0's run is whole: nothing was deleted
        after = sorted(p.relative_to(group) for p in (group / f"seed-{seed}").rglob("*"))
        assert after == before[seed]
    assert (group / "seed-0" / "checkpoints" / "last.pt").is_file()


def rows(run_dir):
    """metrics.jsonl without its timing fields (time/*, SPS): what a resume must reproduce."""
    import json

    return [{key: value for key, value in json.loads(line).items()
             if not key.startswith("time/") and key != "charts/SPS"}
            for line in (run_dir / "metrics.jsonl").read_text().splitlines()]  # fmt: skip


# 12-step episodes: episodes end inside the 4 iterations of 8 steps, across the interruption;
# a fixed learning rate (a linear schedule is stretched by a larger --total-steps)
EPISODES = ["--set", "env.episode_steps=12", "--set", "log_interval=1", "--set",
            "ppo.lr_schedule=fixed"]  # fmt: skip


@pytest.mark.parametrize("seeds", [1, 2])
def test_a_group_resumed_from_its_checkpoints_equals_the_uninterrupted_group(
    tmp_path, capsys, seeds
):
    straight, split = tmp_path / "straight", tmp_path / "split"
    base = ["train", "--seeds", str(seeds), "--seed", "5", *TINY, *EPISODES]
    assert main([*base, "--total-steps", "64", "--run-dir", str(straight)]) == 0
    assert main([*base, "--total-steps", "32", "--run-dir", str(split)]) == 0
    # a kill -9 while the seeds' checkpoints of iteration 3 were written: only the first has
    # them (and its metrics row); the group resumes from iteration 2, the last common one
    last = split / "seed-5" / "checkpoints"
    resume = ["train", "--seeds", str(seeds), "--resume", "--run-dir", str(split),
              "--total-steps", "64", "--no-progress"]  # fmt: skip
    if seeds == 2:
        assert main(resume[:2] + ["1"] + resume[3:]) == 2  # a group of 2, resumed as 1
        assert "is a group of 2 seeds (5-6); resume it with --seeds 2" in capsys.readouterr().err
        straight_first = straight / "seed-5" / "checkpoints"
        for name in ("iter_000003.pt", "last.pt"):  # seed 5 one iteration ahead
            (last / name).write_bytes((straight_first / "iter_000003.pt").read_bytes())
        with (split / "seed-5" / "metrics.jsonl").open("a") as f:
            f.write((straight / "seed-5" / "metrics.jsonl").read_text().splitlines()[3] + "\n")
    capsys.readouterr()
    assert main(resume) == 0
    out = capsys.readouterr().out
    assert f"resuming the group of {seeds} seeds" in out and "at iteration 2" in out
    for seed in range(5, 5 + seeds):
        a, b = rows(straight / f"seed-{seed}"), rows(split / f"seed-{seed}")
        assert [row["iteration"] for row in b] == [1, 2, 3, 4]
        assert a == b, seed  # every row after the interruption, number for number
        ours = torch.load(split / f"seed-{seed}" / "checkpoints" / "last.pt", weights_only=True)
        theirs = torch.load(straight / f"seed-{seed}" / "checkpoints" / "last.pt",
                            weights_only=True)  # fmt: skip
        for key, value in theirs["agent_state"].items():
            assert torch.equal(value, ours["agent_state"][key]), key


def test_a_seed_of_a_group_resumed_alone_says_it_is_not_the_group_continued(tmp_path, capsys):
    group = tmp_path / "group"
    argv = ["train", "--seeds", "2", "--total-steps", "16", "--run-dir", str(group), *TINY]
    assert main(argv) == 0
    capsys.readouterr()
    alone = ["train", "--resume", "--run-dir", str(group / "seed-1"), "--total-steps", "32",
             "--no-progress"]  # fmt: skip
    assert main(alone) == 0
    notes = [line for line in capsys.readouterr().out.splitlines() if line.startswith("note:")]
    assert len(notes) == 1 and "not equal to the group continued" in notes[0]
    assert f"--seeds 2 --resume --run-dir {group}" in notes[0]
    # seed 1 went on alone: the group can no longer continue together (one line)
    assert main(["train", "--seeds", "2", "--resume", "--run-dir", str(group)]) == 2
    err = capsys.readouterr().err
    assert "is not this group's (the seed was resumed alone since)" in err
    assert len(err.strip().splitlines()) == 1


def test_a_group_of_one_seed_resumed_alone_equals_the_uninterrupted_group(tmp_path, capsys):
    straight, split = tmp_path / "straight", tmp_path / "split"
    base = ["train", "--seeds", "1", "--seed", "5", *TINY, *EPISODES]
    assert main([*base, "--total-steps", "64", "--run-dir", str(straight)]) == 0
    assert main([*base, "--total-steps", "32", "--run-dir", str(split)]) == 0
    capsys.readouterr()
    alone = ["train", "--resume", "--run-dir", str(split / "seed-5"), "--total-steps", "64",
             "--no-progress"]  # fmt: skip
    assert main(alone) == 0
    assert "note:" not in capsys.readouterr().out  # nothing to say: it is exact
    assert rows(straight / "seed-5") == rows(split / "seed-5")
