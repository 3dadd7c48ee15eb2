"""A folder cpg-actor writes its outputs into is never a symbolic link: a link there may lead
into a user's folder, so train, eval, export, reproduce and sweep refuse it (one line) and
write nothing through it."""

import pytest

from cpg_actor.cli import main

# 2 envs x 8 steps per iteration, eager
TINY = ["--set", "ppo.compile=false", "--num-envs", "2", "--set", "ppo.num_steps=8",
        "--set", "ppo.num_minibatches=2", "--set", "ppo.num_epochs=1", "--set",
        "eval_interval=0", "--no-progress"]  # fmt: skip


def tree(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def refused(capsys, argv, link):
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"{link} is a symbolic link" in err and len(err.strip().splitlines()) == 1, err


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    run_dir = tmp_path_factory.mktemp("trained") / "run"
    assert main(["train", "--run-dir", str(run_dir), "--total-steps", "16", *TINY]) == 0
    return run_dir


def users_folder(tmp_path):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep")
    return mine


@pytest.mark.parametrize("folder", ["eval", "export"])
def test_eval_and_export_refuse_a_runs_output_folder_that_is_a_link(
    trained, tmp_path, capsys, folder
):
    mine = users_folder(tmp_path)
    link = trained / folder
    link.symlink_to(mine, target_is_directory=True)
    try:
        if folder == "eval":
            refused(capsys, ["eval", str(trained), "--episodes", "1"], link)
            refused(capsys, ["eval", str(trained), "--episodes", "1", "--grid"], link)
        else:
            refused(capsys, ["export", str(trained), "--format", "torchscript"], link)
        assert tree(mine) == ["notes.txt"] and (mine / "notes.txt").read_text() == "keep"
    finally:
        link.unlink()


def test_train_refuses_a_run_directory_or_its_folders_that_are_links(trained, tmp_path, capsys):
    mine = users_folder(tmp_path)
    empty = tmp_path / "empty"
    empty.mkdir()
    link = tmp_path / "linked-run"
    link.symlink_to(empty, target_is_directory=True)
    refused(capsys, ["train", "--run-dir", str(link), "--total-steps", "16", *TINY], link)
    refused(capsys, ["train", "--seeds", "2", "--run-dir", str(link), "--total-steps", "16",
                     *TINY], link)  # fmt: skip
    assert tree(empty) == []
    for folder in ("checkpoints", "tensorboard"):
        kept = trained.parent / f"kept-{folder}"
        (trained / folder).rename(kept)
        (trained / folder).symlink_to(mine, target_is_directory=True)
        try:
            argv = ["train", "--run-dir", str(trained), "--resume", "--total-steps", "32"]
            refused(capsys, [*argv, "--no-progress"], trained / folder)
            refused(capsys, ["train", "--run-dir", str(trained), "--overwrite",
                             "--total-steps", "16", *TINY], trained / folder)  # fmt: skip
        finally:
            (trained / folder).unlink()
            kept.rename(trained / folder)
        assert tree(mine) == ["notes.txt"]
    group = tmp_path / "group"
    (group / "seed-1").mkdir(parents=True)
    (group / "seed-1" / "checkpoints").symlink_to(mine, target_is_directory=True)
    argv = ["train", "--seeds", "2", "--run-dir", str(group), "--total-steps", "16", *TINY]
    refused(capsys, argv, group / "seed-1" / "checkpoints")
    assert not (group / "seed-0").exists() and tree(mine) == ["notes.txt"]


@pytest.mark.parametrize("command", ["reproduce", "sweep"])
def test_reproduce_and_sweep_refuse_an_out_folder_that_is_a_link(tmp_path, capsys, command):
    mine = users_folder(tmp_path)
    argv = [command, "--variants", "mlp", "--seeds", "1", "--total-steps", "32", "--workers",
            "1", "--no-progress", "--set", "ppo.compile=false"]  # fmt: skip
    link = tmp_path / "out"
    link.symlink_to(mine, target_is_directory=True)
    refused(capsys, [*argv, "--out", str(link)], link)
    link.unlink()
    out = tmp_path / "real"
    inner = out / ("default" if command == "sweep" else "") / "logs"
    inner.parent.mkdir(parents=True)
    inner.symlink_to(mine, target_is_directory=True)
    refused(capsys, [*argv, "--out", str(out)], inner)
    assert tree(mine) == ["notes.txt"]
    assert tree(out) == sorted(str(p.relative_to(out)) for p in (inner.parent, inner)
                               if p != out)  # nothing written beside the link  # fmt: skip
