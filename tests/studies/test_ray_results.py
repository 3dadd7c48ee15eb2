"""How a Ray run reaches the head without a shared file system (packed, and merged into the
head's copy), and the one-line errors for a Ray address that does not answer or refuses this
process's token. No Ray needed."""

import shutil
import socket
from pathlib import Path

import pytest

from cpg_actor_studies.reproduction import execute
from cpg_actor_studies.reproduction.plan import ReproduceSettings, build_tasks


@pytest.fixture
def closed_port():
    """A port on 127.0.0.1 that refuses connections (bound, not listening: nobody takes it)."""
    with socket.socket() as holder:
        holder.bind(("127.0.0.1", 0))
        yield holder.getsockname()[1]


def returned_run(tmp_path):
    """A run's copy on the head, packed and sent to a node, which trains on (and removes a
    checkpoint of an earlier attempt) and returns it: ``(head, log, sent, returned)``."""
    head = tmp_path / "out" / "runs" / "mlp" / "seed0"
    (head / "checkpoints").mkdir(parents=True)
    (head / "checkpoints" / "last.pt").write_bytes(b"iteration 1")
    (head / "checkpoints" / "stale.pt").write_bytes(b"from an earlier attempt")
    (head / ".lock").write_text("the head's lock file")
    log = tmp_path / "out" / "logs" / "mlp_seed0.log"
    log.parent.mkdir()
    log.write_text("$ cpg-actor train ...\n")
    sent = {p.relative_to(head).as_posix(): (p.stat().st_size, p.stat().st_mtime_ns)
            for p in head.rglob("*") if p.is_file() and p.name != ".lock"}  # fmt: skip
    data = execute.pack_run(head, log)

    worker = tmp_path / "worker" / "run"
    worker_log = tmp_path / "worker" / "run.log"
    execute.unpack_run(data, worker, worker_log)
    assert not (worker / ".lock").exists()  # a lock is the node's, not the run's
    (worker / "checkpoints" / "last.pt").write_bytes(b"iteration 2")
    (worker / "checkpoints" / "stale.pt").unlink()
    (worker / "metrics.jsonl").write_text('{"global_step": 32}\n')
    (worker / ".lock").write_text("held by a process on the worker")
    worker_log.write_text("$ cpg-actor train ...\n$ cpg-actor train --resume ...\n")
    return head, log, sent, execute.pack_run(worker, worker_log)


def test_a_returned_run_is_merged_keeping_the_files_added_on_the_head_meanwhile(tmp_path):
    head, log, _, returned = returned_run(tmp_path)
    (head / "notes.md").write_text("mine")
    (head / "checkpoints" / "best_of_mine.pt").write_bytes(b"mine")
    execute.unpack_run(returned, head, log)
    assert (head / "checkpoints" / "last.pt").read_bytes() == b"iteration 2"
    assert (head / "metrics.jsonl").is_file() and "--resume" in log.read_text()
    assert (head / "notes.md").read_text() == "mine"
    assert (head / "checkpoints" / "best_of_mine.pt").read_bytes() == b"mine"
    assert (head / ".lock").read_text() == "the head's lock file"
    assert sorted(p.name for p in head.parent.iterdir()) == ["seed0"]  # no temporary left
    assert execute.pack_run(tmp_path / "none", tmp_path / "none.log") is None


def test_a_returned_run_drops_what_the_run_removed_and_writes_through_no_link(tmp_path):
    head, log, sent, returned = returned_run(tmp_path)
    assert execute.run_files(head) == sent  # what run_ray keeps of what it sends
    (head / "notes.md").write_text("mine")
    execute.unpack_run(returned, head, log, sent)
    assert not (head / "checkpoints" / "stale.pt").exists()  # sent, and removed by the run
    assert (head / "notes.md").read_text() == "mine"
    assert (head / "checkpoints" / "last.pt").read_bytes() == b"iteration 2"

    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    shutil.rmtree(head / "checkpoints")
    (head / "checkpoints").symlink_to(elsewhere)
    with pytest.raises(FileExistsError, match="checkpoints is a symbolic link"):
        execute.unpack_run(returned, head, log, sent)
    assert list(elsewhere.iterdir()) == []


def test_a_task_runs_in_its_scratch_directory_with_absolute_paths(tmp_path):
    settings = ReproduceSettings(variants=["mlp"], seeds=1, total_steps=1000, num_envs=8)
    (task,) = build_tasks(settings, tmp_path / "out", workers=1)
    local = execute._in_scratch(task, tmp_path / "scratch")
    args = local.train_args
    assert args[args.index("--run-dir") + 1] == str(tmp_path / "scratch" / "run")
    assert local.run_dir == str(tmp_path / "scratch" / "run")
    assert local.log_path == str(tmp_path / "scratch" / "run.log")
    assert local.name == task.name
    # on the nodes, paths are absolute: a Ray worker's working directory is not the head's
    (relative,) = build_tasks(settings, Path("out"), workers=1)
    absolute = execute._absolute(relative)
    assert absolute.run_dir == str(Path.cwd() / "out" / "runs" / "mlp" / "seed0")
    assert absolute.train_args[absolute.train_args.index("--run-dir") + 1] == absolute.run_dir
    assert absolute.log_path == str(Path.cwd() / "out" / "logs" / "mlp_seed0.log")


def test_an_address_that_does_not_answer_is_one_line(monkeypatch, closed_port):
    port = closed_port
    with pytest.raises(ConnectionError) as error:
        execute.check_reachable(f"127.0.0.1:{port}", timeout=5)
    text = str(error.value)
    assert f"cannot reach the Ray head at 127.0.0.1:{port} within 5 s" in text
    assert "\n" not in text
    with pytest.raises(ConnectionError, match="ray://127.0.0.1"):
        execute.check_reachable(f"ray://127.0.0.1:{port}", timeout=5)
    monkeypatch.setenv("RAY_ADDRESS", f"127.0.0.1:{port}")  # what "auto" connects to
    with pytest.raises(ConnectionError):
        execute.check_reachable("auto", timeout=5)
    monkeypatch.delenv("RAY_ADDRESS")
    execute.check_reachable("auto")  # Ray looks for a cluster on this machine itself


def test_a_refused_token_says_how_to_set_one(monkeypatch, tmp_path):
    # what ray.init raises when the cluster refuses the token: the reason is in the cause
    try:
        try:
            raise RuntimeError("Failed to connect to GCS. ... RPC error: InvalidAuthToken: ...")
        except RuntimeError as cause:
            raise ConnectionError("Failed to connect to Ray cluster at 10.0.0.1:6379") from cause
    except ConnectionError as error:
        refused = error
    monkeypatch.delenv("RAY_AUTH_MODE", raising=False)
    text = execute._connect_error("10.0.0.1:6379", refused)
    assert "refused this process's authentication token" in text
    assert "RAY_AUTH_MODE is not 'token' here" in text
    assert "`ray get-auth-token`" in text and "RAY_AUTH_TOKEN=<token>" in text
    assert "\n" not in text
    monkeypatch.setenv("RAY_AUTH_MODE", "token")
    monkeypatch.setenv("RAY_AUTH_TOKEN_PATH", str(tmp_path / "missing"))
    monkeypatch.delenv("RAY_AUTH_TOKEN", raising=False)
    text = execute._connect_error("10.0.0.1:6379", refused)
    assert f"RAY_AUTH_TOKEN_PATH names {tmp_path / 'missing'}, which does not exist" in text
    other = execute._connect_error("10.0.0.1:6379", ConnectionError("Failed to connect"))
    assert other.startswith("cannot connect to the Ray cluster at 10.0.0.1:6379: Failed")
