"""docs/results/sitting.py: a reproduction's runs carried from one machine to the next, the
finished ones without checkpoints, the unfinished ones with the few a resume and the stage
evaluations need; nothing that exists is overwritten."""

import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tarfile
from pathlib import Path

import pytest
import yaml

from cpg_actor_studies.reproduction.execute import MARKER, trained_iteration

SCRIPT = Path(__file__).resolve().parents[1] / "docs" / "results" / "sitting.py"


def run_script(*args) -> subprocess.CompletedProcess:
    """The script as a reader runs it, with this checkout's package."""
    env = {**os.environ, "PYTHONPATH": str(SCRIPT.parents[2] / "src")}
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True,
                          text=True, env=env)  # fmt: skip


@pytest.fixture(scope="module")
def sitting():
    spec = importlib.util.spec_from_file_location("sitting", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """A tiny run of 6 iterations with a checkpoint after each."""
    from tiny import trained_run  # tests/tiny.py

    return trained_run(tmp_path_factory.mktemp("run") / "seed0", "mlp", total_steps=96,
                       checkpoint_interval=1)  # fmt: skip


def test_an_unfinished_run_is_carried_with_the_checkpoints_it_needs(sitting, trained, tmp_path):
    out = tmp_path / "out"
    run = out / "runs" / "mlp" / "seed0"
    shutil.copytree(trained, run)
    config = yaml.safe_load((run / "config.yaml").read_text())
    config["total_steps"] = 960  # planned 60 iterations: 6 done, the first stage (1/60) passed
    (run / "config.yaml").write_text(yaml.safe_dump(config))
    kept = [p.name for p in sitting.kept_checkpoints(run, (1 / 60, 1 / 3, 1.0))]
    assert kept == ["iter_000000.pt", "iter_000001.pt", "iter_000006.pt"]

    archive = tmp_path / "archive"
    sitting.save(out, archive)  # without --unfinished: nothing to carry
    assert not (archive / "mlp").exists()
    sitting.save(out, archive, unfinished=True)
    assert (archive / "mlp" / "seed0.partial.tar.gz").is_file()

    again = tmp_path / "again"
    sitting.restore(archive, again)
    restored = again / "runs" / "mlp" / "seed0"
    assert sorted(p.name for p in (restored / "checkpoints").iterdir()) == kept
    assert trained_iteration(restored) == trained_iteration(run) == 6
    assert (restored / "metrics.jsonl").read_bytes() == (run / "metrics.jsonl").read_bytes()

    # a run started over (a sitting that did not restore) does not replace a further archive
    behind = tmp_path / "behind"
    shutil.copytree(out, behind)
    for name in ("iter_000003.pt", "iter_000004.pt", "iter_000005.pt", "iter_000006.pt"):
        (behind / "runs" / "mlp" / "seed0" / "checkpoints" / name).unlink()
    sitting.save(behind, archive, unfinished=True)
    assert sitting.archived_iteration(archive / "mlp" / "seed0.partial.tar.gz") == 6
    assert not list(archive.rglob("*.tmp"))

    # finished: its archive has no checkpoints and replaces the partial one
    (run / MARKER).write_text(json.dumps({"status": "done"}))
    sitting.save(out, archive, unfinished=True)
    assert not (archive / "mlp" / "seed0.partial.tar.gz").exists()

    with tarfile.open(archive / "mlp" / "seed0.tar.gz") as tar:
        names = tar.getnames()
    assert MARKER in names and not any(n.startswith("checkpoints") for n in names)

    # a run directory that exists is kept as it is
    (restored / "metrics.jsonl").write_text("mine\n")
    sitting.restore(archive, again)
    assert (restored / "metrics.jsonl").read_text() == "mine\n"


def test_a_sweep_is_carried_setting_by_setting_and_its_command_goes_on(sitting, trained, tmp_path):
    from cpg_actor.files import MARKER as PROJECT_MARKER
    from cpg_actor.files import RESULTS, SWEEP, marker_kind, write_marker
    from cpg_actor_studies import sweep

    out = tmp_path / "sweep"
    out.mkdir()
    write_marker(out, SWEEP)
    out_labels = ("defaults", "ppo.lr=0.001")  # the first finished, the second not
    for label in out_labels:
        setting = out / label
        shutil.copytree(trained, setting / "runs" / "mlp" / "seed0")
        write_marker(setting, RESULTS)
        (setting / "reproduce.yaml").write_text(yaml.safe_dump({"settings": {"seeds": 1}}))
    (out / "defaults" / "runs" / "mlp" / "seed0" / MARKER).write_text('{"status": "done"}')

    archive = tmp_path / "archive"
    sitting.save(out, archive, unfinished=True)
    assert marker_kind(archive) == SWEEP
    assert (archive / "defaults" / "mlp" / "seed0.tar.gz").is_file()
    assert (archive / "ppo.lr=0.001" / "mlp" / "seed0.partial.tar.gz").is_file()
    assert oct((archive / "defaults" / "mlp" / "seed0.tar.gz").stat().st_mode & 0o777) == "0o644"

    again = tmp_path / "again"
    sitting.restore(archive, again)
    assert marker_kind(again) == SWEEP and marker_kind(again / "defaults") == RESULTS
    finished, unfinished = (again / label / "runs" / "mlp" / "seed0" for label in out_labels)
    assert (finished / MARKER).read_text() == '{"status": "done"}'
    assert not (finished / "checkpoints").exists()  # a finished run travels without them
    assert trained_iteration(unfinished) == 6
    for label in out_labels:
        run = out / label / "runs" / "mlp" / "seed0"
        restored = again / label / "runs" / "mlp" / "seed0"
        assert (restored / "metrics.jsonl").read_bytes() == (run / "metrics.jsonl").read_bytes()
        assert (again / label / "reproduce.yaml").read_text() == (
            out / label / "reproduce.yaml"
        ).read_text()
    sweep.prepare_out_dir(again)  # the same `cpg-actor sweep` command accepts the folder
    assert (again / PROJECT_MARKER).read_bytes() == (out / PROJECT_MARKER).read_bytes()


def test_without_traces_a_finished_run_travels_without_its_stage_traces(sitting, trained, tmp_path):
    out = tmp_path / "out"
    run = out / "runs" / "mlp" / "seed0"
    shutil.copytree(trained, run)
    (run / MARKER).write_text(json.dumps({"status": "done"}))
    stage = run / "eval" / "stage0"
    stage.mkdir(parents=True)
    for name in ("traces.npz", "traces.png"):
        (stage / name).write_bytes(b"x" * 100)
    (run / "eval" / "stages.json").write_text("[]\n")

    sitting.save(out, tmp_path / "light", traces=False)
    sitting.save(out, tmp_path / "full")
    with tarfile.open(tmp_path / "light" / "mlp" / "seed0.tar.gz") as tar:
        light = set(tar.getnames())
    with tarfile.open(tmp_path / "full" / "mlp" / "seed0.tar.gz") as tar:
        full = set(tar.getnames())
    assert full - light == {"eval/stage0/traces.npz", "eval/stage0/traces.png"}
    assert {"eval/stages.json", "metrics.jsonl", MARKER} <= light
    assert stage.joinpath("traces.npz").is_file()  # the run itself keeps them


def _archive(path: Path, members: list[tuple[str, bytes | None, str | None]]) -> Path:
    """A tar.gz of ``(name, data, link)`` members: a file (data), a folder (neither) or a
    symbolic link (link)."""
    import io

    path.parent.mkdir(parents=True, exist_ok=True)
    with tarfile.open(path, "w:gz") as tar:
        for name, data, link in members:
            info = tarfile.TarInfo(name)
            if link is not None:
                info.type, info.linkname = tarfile.SYMTYPE, link
            elif data is None:
                info.type = tarfile.DIRTYPE
            else:
                info.size = len(data)
            tar.addfile(info, io.BytesIO(data) if data is not None else None)
    return path


def test_a_damaged_archive_is_refused_in_one_line_and_leaves_no_folder_behind(sitting, tmp_path):
    good = _archive(tmp_path / "good.tar.gz", [("config.yaml", b"agent: mlp\n", None)])
    damaged = {
        "truncated gzip": good.read_bytes()[: len(good.read_bytes()) // 2],
        "not a tar": b"hello, not an archive\n",
    }
    crafted = {
        "outside": [("config.yaml", b"x", None), ("../../escaped.txt", b"x", None)],
        "absolute": [(str(tmp_path / "absolute.txt"), b"x", None)],
        "a link": [("config.yaml", b"x", None), ("link", None, "/etc/passwd")],
        "a relative link": [("link", None, "config.yaml")],
    }
    cases = {**damaged, **crafted}
    for number, case in enumerate(cases):
        archive = tmp_path / f"archive{number}"
        packed = archive / "mlp" / "seed0.tar.gz"
        if case in damaged:
            packed.parent.mkdir(parents=True)
            packed.write_bytes(damaged[case])
        else:
            _archive(packed, crafted[case])
        out = tmp_path / f"out{number}"
        (out / "runs" / "mlp" / "seed1").mkdir(parents=True)  # the user's, kept
        (out / "notes.txt").write_text("mine\n")
        with pytest.raises(ValueError, match=r"seed0.tar.gz"):
            sitting.restore(archive, out)
        assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*")) == [
            "notes.txt",
            "runs",
            "runs/mlp",
            "runs/mlp/seed1",
        ], case  # no .restore-XXXX folder, nothing unpacked; the user's folders kept
        fresh = tmp_path / f"fresh{number}"  # the folders made for it are removed too
        done = run_script("restore", archive, fresh)
        assert done.returncode != 0 and len(done.stderr.splitlines()) == 1, (case, done.stderr)
        assert done.stderr.startswith("sitting.py restore: error: "), done.stderr
        assert not fresh.exists(), case
    assert not (tmp_path / "escaped.txt").exists() and not (tmp_path / "absolute.txt").exists()


def test_save_and_restore_refuse_bad_folders_and_files_in_one_line(sitting, trained, tmp_path):
    (tmp_path / "a file").write_text("mine\n")
    out = tmp_path / "out"
    shutil.copytree(trained, out / "runs" / "mlp" / "seed0")
    cases = [
        (("save", tmp_path / "missing", tmp_path / "archive"), "is not a folder"),
        (("save", tmp_path / "a file", tmp_path / "archive"), "is not a folder"),
        (("save", tmp_path, tmp_path / "archive"), "neither runs/ nor reproduce.yaml"),
        (("save", out, tmp_path / "a file"), "is a file"),
        (("save", out, tmp_path / "a file" / "archive"), "is a file"),
        (("restore", tmp_path / "missing", tmp_path / "again"), "is not a folder"),
    ]
    for args, message in cases:
        done = run_script(*args)
        assert done.returncode != 0 and len(done.stderr.splitlines()) == 1, (args, done.stderr)
        assert message in done.stderr, (args, done.stderr)
    assert not (tmp_path / "archive").exists() and not (tmp_path / "again").exists()
    assert (tmp_path / "a file").read_text() == "mine\n"

    (out / "reproduce.yaml").write_text("settings: [\n")
    with pytest.raises(ValueError, match="reproduce.yaml is not the reproduce.yaml"):
        sitting.save(out, tmp_path / "archive")
    (out / "reproduce.yaml").unlink()
    partial = tmp_path / "archive" / "mlp" / "seed0.partial.tar.gz"
    partial.parent.mkdir(parents=True)
    partial.write_bytes(b"not an archive")  # a damaged partial archive: kept, refused
    with pytest.raises(ValueError, match="seed0.partial.tar.gz is damaged"):
        sitting.save(out, tmp_path / "archive", unfinished=True)
    assert partial.read_bytes() == b"not an archive"
