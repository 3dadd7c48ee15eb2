"""`cpg-actor reproduce --ray HOST:PORT` on a Ray cluster of two nodes on this machine, as on
several machines: a head and a worker node, each its own `ray start` process, with Ray's token
authentication. Two runs, one per node (one CPU each), come back to the head's OUT as their
tasks' results (``--ray-results return``: as without a shared file system); a wrong token is
refused with one line. About 2-3 minutes on 2 busy cores."""

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

import cpg_actor

pytest.importorskip("ray")
pytestmark = pytest.mark.slow

RAY = [sys.executable, "-m", "ray.scripts.scripts"]  # the `ray` command of this Python
STARTED = "Ray runtime started."
TINY = [
    "--variants", "mlp", "--seeds", "2", "--total-steps", "32", "--num-envs", "4",
    "--set", "ppo.num_steps=8", "--set", "ppo.num_minibatches=2", "--set", "ppo.num_epochs=1",
    "--set", "env.episode_steps=10", "--eval-episodes", "1", "--no-progress",
    "--set", "ppo.compile=false",
]  # fmt: skip


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _start(args: list[str], env: dict[str, str], log: Path) -> subprocess.Popen:
    """``ray start ARGS --block`` in a process group of its own (stopped by its id)."""
    with open(log, "w") as out:
        return subprocess.Popen(
            [*RAY, "start", *args, "--block", "--num-cpus", "1", "--node-ip-address",
             "127.0.0.1", "--disable-usage-stats"],
            env=env, stdout=out, stderr=subprocess.STDOUT, start_new_session=True,
        )  # fmt: skip


def _wait_started(process: subprocess.Popen, log: Path, what: str, timeout: float = 180) -> None:
    deadline = time.monotonic() + timeout
    while STARTED not in log.read_text():
        if process.poll() is not None or time.monotonic() > deadline:
            tail = " | ".join(log.read_text().strip().splitlines()[-3:])
            pytest.skip(f"`ray start` ({what}) cannot run here: {tail}")
        time.sleep(0.5)


def _stop(process: subprocess.Popen) -> None:
    """SIGTERM to a `ray start --block` stops its node's processes; then its group, if any
    is left."""
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=60)
        except subprocess.TimeoutExpired:
            pass
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    process.wait()


@pytest.fixture
def cluster():
    """``(address, env)`` of a head and a worker node of one CPU each; ``env`` holds the token
    (RAY_AUTH_MODE=token, RAY_AUTH_TOKEN_PATH) and makes Ray's workers import this code."""
    base = Path(tempfile.mkdtemp(prefix="cpgray-"))  # short: Ray's socket paths are limited
    env = {k: v for k, v in os.environ.items() if not k.startswith("RAY_")}
    env["HOME"] = str(base / "home")  # `ray get-auth-token --generate` writes ~/.ray/auth_token
    source = str(Path(cpg_actor.__file__).resolve().parent.parent)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [source, env.get("PYTHONPATH")]))
    processes: list[subprocess.Popen] = []
    try:
        generated = subprocess.run(
            [*RAY, "get-auth-token", "--generate"], env=env, capture_output=True, text=True,
            timeout=120,
        )  # fmt: skip
        token = generated.stdout.strip()
        if generated.returncode != 0 or not token:
            pytest.skip(f"`ray get-auth-token --generate` cannot run here: {generated.stderr}")
        env["RAY_AUTH_MODE"] = "token"
        env["RAY_AUTH_TOKEN_PATH"] = str(base / "home" / ".ray" / "auth_token")
        assert Path(env["RAY_AUTH_TOKEN_PATH"]).read_text().strip() == token

        port = _free_port()
        head_args = ["--head", "--port", str(port), "--ray-client-server-port", str(_free_port())]
        head_args += ["--include-dashboard", "false", "--temp-dir", str(base / "head")]
        processes.append(_start(head_args, env, base / "head.log"))
        _wait_started(processes[0], base / "head.log", "head")
        worker_args = ["--address", f"127.0.0.1:{port}", "--temp-dir", str(base / "worker")]
        processes.append(_start(worker_args, env, base / "worker.log"))
        _wait_started(processes[1], base / "worker.log", "worker node")
        yield f"127.0.0.1:{port}", env
    finally:
        for process in reversed(processes):
            _stop(process)
        shutil.rmtree(base, ignore_errors=True)


def test_two_nodes_run_one_seed_each_and_return_it_to_the_head(cluster, tmp_path):
    address, env = cluster
    out = tmp_path / "results"
    command = [sys.executable, "-m", "cpg_actor.cli", "reproduce", "--out", str(out)]
    command += ["--ray", address, "--ray-results", "return", *TINY]
    done = subprocess.run(
        command, env=env, cwd=tmp_path, capture_output=True, text=True, timeout=900
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert f"Ray at {address}" in done.stdout

    nodes = {}
    for seed in (0, 1):
        run = out / "runs" / "mlp" / f"seed{seed}"
        marker = json.loads((run / "reproduce_run.json").read_text())
        assert marker["status"] == "done"
        assert marker["node"]["files"] == "returned"  # trained elsewhere, unpacked here
        nodes[seed] = marker["node"]["id"]
        assert (run / "config.yaml").is_file() and (run / "metrics.jsonl").is_file()
        assert (run / "checkpoints" / "last.pt").is_file()
        assert (run / "eval" / "stage0" / "traces.npz").is_file()
        assert "$ cpg-actor eval" in (out / "logs" / f"mlp_seed{seed}.log").read_text()
    assert nodes[0] != nodes[1]  # one run on each node
    report = (out / "report.md").read_text()
    assert "Ray nodes this invocation (2)" in report
    assert "(`mlp`) | 2 (2) |" in report
    assert (out / "summary.json").is_file()

    # a process without the cluster's token: refused, in one line, before OUT is written
    wrong = {k: v for k, v in env.items() if k != "RAY_AUTH_TOKEN_PATH"}
    wrong["RAY_AUTH_TOKEN"] = "0" * 64
    refused = subprocess.run(
        [*command[:5], str(tmp_path / "other"), *command[6:]],
        env=wrong, cwd=tmp_path, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert refused.returncode == 1
    last = refused.stderr.strip().splitlines()[-1]
    assert last.startswith(
        f"cpg-actor reproduce: error: the Ray cluster at {address} refused this process's "
        "authentication token (RAY_AUTH_TOKEN does not match the cluster's token)"
    )
    assert "RAY_AUTH_MODE=token" in last
    assert not (tmp_path / "other").exists()
