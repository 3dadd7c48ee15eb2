"""What a command does with bad input and a damaged or foreign directory: one line saying what
is wrong, nothing a user made deleted, nothing written by a refused command."""

import errno
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from cpg_actor.cli import main
from cpg_actor.files import MARKER
from cpg_actor.training.checkpoint import load_checkpoint, resume_checkpoint

TINY = [
    "--set", "ppo.compile=false", "--num-envs", "2", "--set", "ppo.num_steps=8",
    "--set", "ppo.num_minibatches=2", "--set", "ppo.num_epochs=1",
    "--set", "checkpoint_interval=1", "--set", "eval_interval=0", "--no-progress",
]  # fmt: skip
STEPS = 16  # per iteration


def train(run_dir: Path, iterations: int, *extra: str) -> int:
    return main(["train", "--run-dir", str(run_dir), "--total-steps", str(iterations * STEPS),
                 *TINY, *extra])  # fmt: skip


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def tree(directory: Path) -> dict[str, bytes]:
    return {
        str(path.relative_to(directory)): path.read_bytes()
        for path in sorted(directory.rglob("*"))
        if path.is_file()
    }


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> Path:
    """A finished tiny run (2 iterations, a checkpoint at each); copy it before changing it."""
    run_dir = tmp_path_factory.mktemp("trained") / "run"
    assert train(run_dir, 2) == 0
    return run_dir


def copy_of(run_dir: Path, tmp_path: Path) -> Path:
    copy = tmp_path / "run"
    shutil.copytree(run_dir, copy)
    return copy


# -- --overwrite -------------------------------------------------------------------------------
def test_overwrite_refuses_a_folder_without_the_marker_and_writes_nothing(tmp_path, capsys):
    user = tmp_path / "thesis"
    user.mkdir()
    (user / "config.yaml").write_text("mine: true\n")
    (user / "thesis.tex").write_text("\\documentclass{article}")
    before = tree(user)
    assert train(user, 2, "--overwrite") == 2
    err = one_line(capsys)
    assert "refusing to delete" in err and MARKER in err and str(user) in err
    assert "delete it yourself" in err  # how to proceed with a run made before the marker
    assert tree(user) == before and sorted(p.name for p in user.iterdir()) == [
        "config.yaml",
        "thesis.tex",
    ]  # no lock file, no marker: a refused command writes nothing


def test_overwrite_clears_only_a_marked_run_holding_nothing_foreign(tmp_path, capsys, trained):
    run_dir = copy_of(trained, tmp_path)
    assert (run_dir / MARKER).is_file()
    (run_dir / "checkpoints" / "best_of_mine.pt").write_bytes(b"mine")
    (run_dir / "notes").mkdir()
    before = tree(run_dir)
    assert train(run_dir, 1, "--overwrite") == 2
    err = one_line(capsys)
    assert "files cpg-actor did not write" in err
    assert "checkpoints/best_of_mine.pt" in err and "notes" in err
    assert tree(run_dir) == before and (run_dir / "notes").is_dir()

    (run_dir / "checkpoints" / "best_of_mine.pt").unlink()
    (run_dir / "notes").rmdir()
    assert train(run_dir, 1, "--overwrite") == 0
    assert load_checkpoint(run_dir / "checkpoints" / "last.pt")["iteration"] == 1
    assert not (run_dir / "checkpoints" / "iter_000002.pt").exists()  # the old run is gone
    assert (run_dir / MARKER).is_file()


def test_a_results_directory_is_cleared_only_of_what_reproduce_wrote(tmp_path):
    from cpg_actor_studies.reproduction.plan import ReproduceSettings, prepare_out_dir

    out = tmp_path / "out"
    settings = ReproduceSettings(variants=["mlp"], seeds=1, total_steps=1000)
    other = ReproduceSettings(variants=["mlp"], seeds=1, total_steps=2000)
    assert prepare_out_dir(out, settings, overwrite=False) == "new"
    (out / "reproduce.yaml").write_text(f"settings: {json.dumps(settings.identity())}\n")
    (out / "logs").mkdir()
    (out / "logs" / "mlp_seed0.log").write_text("log")
    (out / "draft.md").write_text("mine")
    with pytest.raises(FileExistsError, match="did not write \\(draft.md\\)"):
        prepare_out_dir(out, other, overwrite=True)
    assert (out / "logs" / "mlp_seed0.log").is_file() and (out / "draft.md").is_file()
    (out / "draft.md").unlink()
    assert prepare_out_dir(out, other, overwrite=True) == "overwrite"
    assert sorted(p.name for p in out.iterdir()) == [MARKER]
    # one made before the marker existed is refused, with what to do
    old = tmp_path / "old"
    old.mkdir()
    (old / "reproduce.yaml").write_text(f"settings: {json.dumps(settings.identity())}\n")
    with pytest.raises(FileExistsError, match="delete it yourself"):
        prepare_out_dir(old, other, overwrite=True)
    assert (old / "reproduce.yaml").is_file()


def test_a_refused_resume_writes_nothing(tmp_path, capsys):
    folder = tmp_path / "folder"
    folder.mkdir()
    (folder / "data.csv").write_text("1,2\n")
    assert main(["train", "--run-dir", str(folder), "--resume", "--total-steps", "32"]) == 2
    assert "holds no checkpoint" in one_line(capsys)
    assert sorted(p.name for p in folder.iterdir()) == ["data.csv"]


# -- nothing a user made is lost --------------------------------------------------------------
def test_eval_output_keeps_the_figures_it_did_not_write(tmp_path, capsys, trained):
    """The figures drawn next to a named --output replace nothing there without --overwrite."""
    folder = tmp_path / "mine"
    folder.mkdir()
    for name in ("training_curves.png", "traces.png"):
        (folder / name).write_bytes(b"my figure")
    before = tree(folder)
    argv = ["eval", str(trained), "--episodes", "1", "--output", str(folder / "x.npz")]
    assert main(argv) == 2
    err = one_line(capsys)
    assert f"{folder / 'training_curves.png'} exists; pass --overwrite" in err
    assert tree(folder) == before  # no traces written either
    assert main([*argv, "--overwrite"]) == 0  # named files the user asked to replace
    assert (folder / "traces.png").read_bytes() != b"my figure" and (folder / "x.npz").is_file()


def test_a_lock_that_is_a_link_is_refused_and_its_target_kept(tmp_path, capsys, trained):
    target = tmp_path / "elsewhere.txt"
    target.write_text("precious")
    run_dir = copy_of(trained, tmp_path)
    (run_dir / ".lock").unlink(missing_ok=True)
    (run_dir / ".lock").symlink_to(target)
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "48"]) == 2
    err = one_line(capsys)
    assert f"{run_dir / '.lock'} is a symbolic link" in err
    assert target.read_text() == "precious"
    assert load_checkpoint(run_dir / "checkpoints" / "last.pt")["iteration"] == 2
    # a folder holding only the link (a new run there) is not empty: refused, the same
    fresh = tmp_path / "fresh"
    fresh.mkdir()
    (fresh / ".lock").symlink_to(target)
    assert train(fresh, 1) == 2
    assert "already exists" in one_line(capsys)
    assert target.read_text() == "precious" and [p.name for p in fresh.iterdir()] == [".lock"]


def test_a_folder_holding_only_a_lock_file_of_its_own_is_not_empty(tmp_path, capsys):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / ".lock").write_text("my lock file")
    assert train(folder, 1) == 2
    assert "already exists" in one_line(capsys)
    assert tree(folder) == {".lock": b"my lock file"}
    # a run's own marker and lock (a start stopped before its first write): a new run starts
    assert train(tmp_path / "run", 1) == 0
    for path in (tmp_path / "run").iterdir():
        if path.name not in (MARKER, ".lock"):
            shutil.rmtree(path) if path.is_dir() else path.unlink()
    assert train(tmp_path / "run", 1) == 0


def test_a_metrics_file_that_is_a_link_gets_no_rows(tmp_path, capsys, trained):
    from cpg_actor.training.run_log import RunLog

    target = tmp_path / "elsewhere.jsonl"
    target.write_text('{"mine": 1}\n')
    run_dir = copy_of(trained, tmp_path)
    (run_dir / "metrics.jsonl").unlink()
    (run_dir / "metrics.jsonl").symlink_to(target)
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "48"]) == 2
    assert f"{run_dir / 'metrics.jsonl'} is a symbolic link" in one_line(capsys)
    assert target.read_text() == '{"mine": 1}\n'
    assert load_checkpoint(run_dir / "checkpoints" / "last.pt")["iteration"] == 2
    with pytest.raises(FileExistsError, match="is a symbolic link"):  # a link made later
        RunLog(run_dir, tensorboard=False).write(3, 48, {"x": 1.0})
    assert target.read_text() == '{"mine": 1}\n'


def test_overwrite_keeps_a_users_file_named_like_a_temporary(tmp_path, capsys, trained):
    run_dir = copy_of(trained, tmp_path)
    (run_dir / ".notes.tmp1234").write_text("my notes")
    assert train(run_dir, 1, "--overwrite") == 2
    assert "did not write (.notes.tmp1234)" in one_line(capsys)
    assert (run_dir / ".notes.tmp1234").read_text() == "my notes"
    assert load_checkpoint(run_dir / "checkpoints" / "last.pt")["iteration"] == 2
    # the temporaries of cpg-actor's own files (a killed write) are its own: cleared
    (run_dir / ".notes.tmp1234").unlink()
    (run_dir / ".config.yaml.tmp4242").write_text("partial")
    (run_dir / "checkpoints" / ".last.pt.tmp17").write_text("partial")
    assert train(run_dir, 1, "--overwrite") == 0
    assert not (run_dir / ".config.yaml.tmp4242").exists()
    assert sorted(p.name for p in (run_dir / "checkpoints").iterdir()) == [
        "iter_000000.pt", "iter_000001.pt", "last.pt"]  # fmt: skip


def test_overwrite_clears_what_eval_export_and_curves_wrote_in_a_run(tmp_path, trained):
    run_dir = copy_of(trained, tmp_path)
    written = [  # the files these commands write in a run directory by default
        "eval/stage0/traces.npz", "eval/stage0/training_curves.png", "eval/stage0/traces.png",
        "eval/stage1/gait_diagram.png", "eval/stage1/forward_speed.png", "eval/stages.json",
        "export/policy.onnx", "export/policy.onnx.initial_state.npy",
        "export/policy.onnx.robot.xml", "export/policy.pt.robot.xml", "curves.png",
        "curves.json", "reproduce_run.json",
    ]  # fmt: skip
    for name in written:
        (run_dir / name).parent.mkdir(parents=True, exist_ok=True)
        (run_dir / name).write_bytes(b"written by cpg-actor")
    assert train(run_dir, 1, "--overwrite") == 0
    assert [name for name in written if (run_dir / name).exists()] == []


def test_a_torn_last_metrics_row_is_dropped_with_a_note_and_resume_continues(
    tmp_path, capsys, trained
):
    run_dir = copy_of(trained, tmp_path)
    metrics = run_dir / "metrics.jsonl"
    with open(metrics, "a") as f:
        f.write('{"iteration": 3, "global_step": 48, "losses/po')  # killed while writing it
    capsys.readouterr()
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "48"]) == 0
    err = capsys.readouterr().err
    assert f"{metrics}: its last row is cut off" in err and "Traceback" not in err
    rows = [json.loads(line) for line in metrics.read_text().splitlines()]
    assert [row["global_step"] for row in rows] == [16, 32, 48]
    # a damaged row before the last is no torn write: refused, naming the file and line
    metrics.write_text('{"iteration": 1, "global_step": 16}\nnot json\n{"iteration": 2}\n')
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "64"]) == 2
    assert f"{metrics}, line 2" in one_line(capsys)


# -- bad paths and values ---------------------------------------------------------------------
@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--seed", str(2**64)], "seed must be an integer from 0 to 2**63-1"),
        (["--seed", str(2**63)], "seed must be an integer from 0 to 2**63-1"),
        (["--seed", "-1"], "seed must be an integer from 0 to 2**63-1"),
        (["--set", f"seed={2**63}"], "seed must be an integer from 0 to 2**63-1"),
    ],
)
def test_a_seed_out_of_range_is_one_line_and_creates_nothing(tmp_path, capsys, argv, message):
    run_dir = tmp_path / "run"
    assert main(["train", "--run-dir", str(run_dir), *argv, *TINY]) == 2
    assert message in one_line(capsys)
    assert not run_dir.exists()


def test_the_largest_seed_is_accepted():
    from cpg_actor.config import MAX_SEED, TrainConfig

    TrainConfig(seed=MAX_SEED).validate()
    with pytest.raises(ValueError, match="from 0 to 2\\*\\*63-1"):
        TrainConfig(seed=MAX_SEED + 1).validate()


def test_a_binary_config_file_is_named_in_one_line(tmp_path, capsys):
    path = tmp_path / "weights.bin"
    path.write_bytes(b"\xff\xfe\x00\x01binary")
    run_dir = tmp_path / "run"
    assert main(["train", "--run-dir", str(run_dir), "--config", str(path), *TINY]) == 2
    err = one_line(capsys)
    assert str(path) in err and "is not a YAML text file" in err
    assert not run_dir.exists()


def test_a_run_dir_that_is_a_file_is_one_line_and_the_file_is_kept(tmp_path, capsys):
    afile = tmp_path / "notes.txt"
    afile.write_text("keep")
    assert train(afile, 2) == 2
    assert f"run directory {afile} is a file" in one_line(capsys)
    assert train(afile / "run", 2) == 2
    assert f"is inside {afile}, a file" in one_line(capsys)
    assert main(["train", "--run-dir", str(afile), "--resume"]) == 2
    assert "is a file" in one_line(capsys)
    assert afile.read_text() == "keep"


def test_a_run_dir_too_long_for_its_files_is_refused_before_anything_starts(tmp_path, capsys):
    path_max = os.pathconf(tmp_path, "PC_PATH_MAX")
    name = "d" * 200
    run_dir = tmp_path
    while len(os.fsencode(str(run_dir / name))) < path_max - 30 - 10:
        run_dir = run_dir / name
    # a directory 30 bytes under the limit: it can be made, the files in it cannot
    run_dir = run_dir / ("e" * (path_max - 30 - len(os.fsencode(str(run_dir))) - 1))
    assert len(os.fsencode(str(run_dir))) == path_max - 30
    top = tmp_path / name
    assert train(run_dir, 2) == 2
    err = one_line(capsys)
    assert "is too long" in err and f"limit of {path_max - 1}" in err
    assert not top.exists()


# -- full disk ---------------------------------------------------------------------------------
def test_a_full_disk_during_a_checkpoint_is_one_line_naming_the_file(
    tmp_path, capsys, monkeypatch, trained
):
    run_dir = copy_of(trained, tmp_path)

    def full_disk(obj, f, *args, **kwargs):
        f.write(b"partial")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(torch, "save", full_disk)
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "64"]) == 1
    err = one_line(capsys)
    target = run_dir / "checkpoints" / "iter_000003.pt"
    assert err == f"cpg-actor train: error: no space left on device while writing {target}\n"
    assert sorted(p.name for p in (run_dir / "checkpoints").iterdir()) == [
        "iter_000000.pt",
        "iter_000001.pt",
        "iter_000002.pt",
        "last.pt",
    ]  # fmt: skip  (no temporary file left; the checkpoints saved before are intact)
    monkeypatch.undo()
    assert load_checkpoint(run_dir / "checkpoints" / "last.pt")["iteration"] == 2


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full (Linux)")
def test_a_disk_that_fills_inside_torch_save_names_the_file_not_torch(tmp_path, monkeypatch):
    """torch's zip writer turns the failed write of a large tensor into a RuntimeError
    ("unexpected pos ..."); the write is reported as the OSError it was."""
    import cpg_actor.files as files
    from cpg_actor.training.checkpoint import atomic_save

    def full(path, mode="r", *args, **kwargs):  # every write of this file hits a full disk
        return open("/dev/full", mode, *args, **kwargs)

    monkeypatch.setattr(files, "open", full, raising=False)
    target = tmp_path / "checkpoints" / "last.pt"
    with pytest.raises(OSError) as raised:
        atomic_save({"weights": torch.zeros(1_000_000)}, target)
    assert raised.value.errno == errno.ENOSPC and raised.value.filename == str(target)
    assert files.describe_os_error(raised.value) == (
        f"no space left on device while writing {target}"
    )
    assert list(target.parent.iterdir()) == []


# -- resume ------------------------------------------------------------------------------------
def test_resume_takes_the_newest_complete_checkpoint(tmp_path, capsys, trained):
    """A run killed between writing iter_000002.pt and last.pt: last.pt is iteration 1."""
    run_dir = copy_of(trained, tmp_path)
    checkpoints = run_dir / "checkpoints"
    shutil.copyfile(checkpoints / "iter_000001.pt", checkpoints / "last.pt")
    path, data, notes = resume_checkpoint(run_dir)
    assert (path.name, data["iteration"], notes) == ("iter_000002.pt", 2, [])
    # a newer one that cannot be read is skipped for the next newest
    (checkpoints / "iter_000003.pt").write_bytes(b"not a checkpoint")
    path, data, notes = resume_checkpoint(run_dir)
    assert (path.name, data["iteration"]) == ("iter_000002.pt", 2)
    assert len(notes) == 1 and "iter_000003.pt" in notes[0]
    (checkpoints / "iter_000003.pt").unlink()
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "32"]) == 2
    assert "already at iteration 2" in one_line(capsys)


def test_resume_removes_the_temporary_files_of_killed_writes_and_only_those(tmp_path, trained):
    run_dir = copy_of(trained, tmp_path)
    stale = [
        run_dir / ".config.yaml.tmp4242",
        run_dir / ".metrics.jsonl.tmp4242",
        run_dir / "checkpoints" / ".last.pt.tmp99999",
        run_dir / "checkpoints" / ".iter_000003.pt.tmp17",
    ]
    kept = [run_dir / ".thesis.tex.tmp1", run_dir / "checkpoints" / "mine.tmp2"]
    for path in stale + kept:
        path.write_bytes(b"x")
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "48"]) == 0
    assert [path.exists() for path in stale] == [False] * len(stale)
    assert [path.read_bytes() for path in kept] == [b"x"] * len(kept)


def test_tensorboard_holds_each_point_once_after_a_resume(tmp_path):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    run_dir = tmp_path / "run"
    assert train(run_dir, 3, "--set", "checkpoint_interval=2") == 0  # checkpoints 0, 2, 3
    checkpoints = run_dir / "checkpoints"
    (checkpoints / "iter_000003.pt").unlink()  # killed before its checkpoint at iteration 3
    shutil.copyfile(checkpoints / "iter_000002.pt", checkpoints / "last.pt")
    # TensorBoard reads event files in name order, and a name starts with the second it was
    # made: a real resume comes later, here the same second would leave the order to the
    # process's writer counter (".10" sorts before ".9"), so the first run's file is dated back
    (old,) = (run_dir / "tensorboard").glob("events.out.tfevents.*")
    stamp = old.name.split(".")[3]
    old.rename(old.with_name(old.name.replace(f".{stamp}.", f".{int(stamp) - 1:010d}.", 1)))
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "48"]) == 0
    rows = [json.loads(line) for line in (run_dir / "metrics.jsonl").read_text().splitlines()]
    assert [row["global_step"] for row in rows] == [16, 32, 48]
    events = EventAccumulator(str(run_dir / "tensorboard"))
    events.Reload()
    steps = [event.step for event in events.Scalars("losses/policy_loss")]
    assert steps == [16, 32, 48]
    last = [row for row in rows if row["global_step"] == 48][0]["losses/policy_loss"]
    value = events.Scalars("losses/policy_loss")[-1].value
    assert value == pytest.approx(last, rel=1e-6)  # the resumed run's point, not the old one


# -- export ------------------------------------------------------------------------------------
def test_export_onto_a_directory_is_one_line_and_leaves_nothing(tmp_path, capsys, trained):
    out = tmp_path / "exported"
    out.mkdir()
    argv = ["export", str(trained), "--format", "torchscript", "--out", str(out)]
    for extra in ([], ["--overwrite"]):
        assert main([*argv, *extra]) == 2
        assert f"{out} is a directory" in one_line(capsys)
        assert sorted(p.name for p in tmp_path.iterdir()) == ["exported"]
        assert list(out.iterdir()) == []


def test_an_export_that_fails_at_its_last_rename_leaves_no_initial_state(
    tmp_path, monkeypatch, trained
):
    import cpg_actor.deploy.export as export
    from cpg_actor.deploy import load_policy

    policy = load_policy(trained / "checkpoints" / "last.pt")
    target = tmp_path / "policy.pt"
    replace = os.replace

    def fail_on_the_policy(src, dst):
        if Path(dst) == target:
            raise OSError(errno.ENOSPC, "No space left on device")
        replace(src, dst)

    monkeypatch.setattr(export.os, "replace", fail_on_the_policy)
    with pytest.raises(OSError, match="No space"):
        export.export_policy(policy, target, "torchscript")
    assert list(tmp_path.iterdir()) == []


# -- actions -----------------------------------------------------------------------------------
COMPLEX = "actions must be real numbers"


@pytest.mark.filterwarnings("error")  # numpy's ComplexWarning would fail the test
def test_complex_actions_are_refused_by_the_hopper_envs():
    from cpg_actor.robots.hopper.env import HopperEnv
    from cpg_actor.robots.hopper.vector import HopperVectorEnv

    env = HopperEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match=COMPLEX):
        env.step(np.array([0.1 + 1j, -0.5]))
    env.close()
    vector = HopperVectorEnv(2)
    vector.reset(seed=0)
    with pytest.raises(ValueError, match=COMPLEX):
        vector.step(np.array([[0.1, -0.5], [0.2j, -0.5]]))
    with pytest.raises(ValueError, match=COMPLEX):
        vector.step(torch.zeros(2, 2, dtype=torch.complex64))
    vector.close()


@pytest.mark.filterwarnings("error")
def test_complex_actions_are_refused_by_the_quadruped_and_cho_envs():
    from cpg_actor.robots.anymal.vector import AnymalVectorEnv
    from cpg_actor.robots.hopper.cho2019 import CPGParameterVectorEnv

    anymal = AnymalVectorEnv(1)
    anymal.reset(seed=0)
    with pytest.raises(ValueError, match=COMPLEX):
        anymal.step(np.zeros((1, 12), dtype=np.complex128))
    anymal.close()
    cho = CPGParameterVectorEnv(2)
    cho.reset(seed=0)
    with pytest.raises(ValueError, match=COMPLEX):
        cho.step(np.full((2, cho.action_dim), 0.5 + 0.5j))
    with pytest.raises(ValueError, match=COMPLEX):
        cho._check_actions(torch.zeros(2, cho.action_dim, dtype=torch.complex64))
    cho.close()


# -- the command line --------------------------------------------------------------------------
IMPORTED = """
import sys
from cpg_actor.cli import main
try:
    main(sys.argv[1:])
except SystemExit:
    pass
heavy = ("torch", "mujoco", "pybullet", "jax", "matplotlib")
print("imported:" + ",".join(name for name in heavy if name in sys.modules))
"""


@pytest.mark.parametrize("argv", [["--version"], ["--help"], []])
def test_version_and_help_import_neither_torch_nor_a_simulator(argv):
    result = subprocess.run(
        [sys.executable, "-c", IMPORTED, *argv], capture_output=True, text=True, timeout=120
    )
    assert result.stdout.splitlines()[-1] == "imported:", result.stdout + result.stderr
    if argv == ["--version"]:
        assert result.stdout.startswith("cpg-actor ")
    if argv == ["--help"]:
        assert "train" in result.stdout and "export" in result.stdout


def test_every_command_has_its_module_help_and_arguments(capsys):
    import importlib

    from cpg_actor.cli import commands

    for name, (module_name, help_text) in commands().items():
        module = importlib.import_module(module_name)
        assert help_text == module.HELP, name
        with pytest.raises(SystemExit) as exit_:
            main([name, "--help"])
        assert exit_.value.code == 0
        out = capsys.readouterr().out
        assert out.startswith(f"usage: cpg-actor {name}") and module.HELP[:40] in out
    with pytest.raises(SystemExit) as exit_:
        main(["no-such-command"])
    assert exit_.value.code == 2
    assert "invalid choice: 'no-such-command'" in capsys.readouterr().err
