"""Execute reproduction runs: one run = train (fresh or resumed) then staged evaluations.

Each step is a ``cpg-actor`` subprocess (``python -m cpg_actor.cli``), so every run has its own
torch / MuJoCo threads and a crash stays inside its run. Locally, ``workers`` threads each wait
on one subprocess at a time; with Ray each run is a task with ``num_cpus=1``. A Ray task writes
the run into ``OUT`` directly where its node sees ``OUT`` (a shared file system), otherwise it
runs in a temporary directory on its node and returns the run directory, packed, as its result
(through Ray's object store); the head unpacks it into ``OUT`` (``RAY_RESULTS``).

A run is *finished* when ``RUN_DIR/reproduce_run.json`` exists with ``status: done``: the
training reached its total steps and every stage evaluation was written. Anything less is
continued: training from ``checkpoints/last.pt`` with ``cpg-actor train --resume``, missing
evaluations are run.
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
import re
import secrets
import shutil
import socket
import subprocess
import sys
import tarfile
import tempfile
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from cpg_actor.api import atomic_write_text
from cpg_actor.files import (
    LOCK,
    RUN,
    clear_project_dir,
    open_own,
    refuse_link,
    refuse_linked_folders,
)
from cpg_actor.machine import PARENT_ENV, git_commit
from cpg_actor.training.run_lock import LOCK_NAME
from cpg_actor_studies.reproduction.plan import RunTask

MARKER = "reproduce_run.json"
STAGES_FILE = "stages.json"
_CHECKPOINT = re.compile(r"^iter_(\d+)\.pt$")

Status = Callable[[str, str], None]  # (run name, state) -> None
STOP = threading.Event()  # set on Ctrl-C: no new subprocess starts


def _single_thread_env() -> dict[str, str]:
    env = dict(os.environ)
    for key in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        env[key] = "1"
    env[PARENT_ENV] = str(os.getpid())  # the run dies with this process (machine.py)
    return env


def _cli(args: list[str], log_path: Path) -> int:
    """Run ``cpg-actor ARGS`` in a subprocess, appending its output to ``log_path``."""
    if STOP.is_set():
        return 130
    log_path.parent.mkdir(parents=True, exist_ok=True)
    command = [sys.executable, "-m", "cpg_actor.cli", *args]
    with open_own(log_path, "a") as log:
        log.write(f"$ cpg-actor {' '.join(args)}\n")
        log.flush()
        return subprocess.call(
            command, stdout=log, stderr=subprocess.STDOUT, env=_single_thread_env()
        )


def list_checkpoints(run_dir: Path) -> dict[int, Path]:
    """``{iteration: path}`` of ``RUN_DIR/checkpoints/iter_XXXXXX.pt``."""
    found = {}
    directory = Path(run_dir) / "checkpoints"
    if directory.is_dir():
        for path in directory.iterdir():
            match = _CHECKPOINT.match(path.name)
            if match:
                found[int(match.group(1))] = path
    return found


def select_stage_checkpoints(
    checkpoints: dict[int, Path], num_iterations: int, fractions: tuple[float, ...]
) -> list[tuple[float, int, Path]]:
    """For each fraction of training, the checkpoint whose iteration is nearest to
    ``fraction * num_iterations`` (ties: the later one): ``[(fraction, iteration, path)]``."""
    if not checkpoints:
        raise ValueError("no checkpoints to choose from")
    chosen = []
    for fraction in fractions:
        target = fraction * num_iterations
        iteration = min(checkpoints, key=lambda i: (abs(i - target), -i))
        chosen.append((fraction, iteration, checkpoints[iteration]))
    return chosen


def trained_iteration(run_dir: Path) -> int | None:
    """The iteration ``train --resume`` would start from: that of the newest readable
    checkpoint (:func:`cpg_actor.training.checkpoint.resume_checkpoint`); None when there is
    none."""
    from cpg_actor.api import resume_checkpoint

    try:
        _, data, _ = resume_checkpoint(Path(run_dir))
        return int(data["iteration"])
    except (ValueError, FileNotFoundError, KeyError):
        return None


def run_is_finished(task: RunTask) -> bool:
    marker = Path(task.run_dir) / MARKER
    if not marker.is_file():
        return False
    try:
        data = json.loads(marker.read_text())
    except ValueError:
        return False
    return data.get("status") == "done" and data.get("total_steps") == task.total_steps


def run_one(
    task: RunTask, status: Status | None = None, node: dict[str, Any] | None = None
) -> dict[str, Any]:
    """Train (or resume) one run, then evaluate it at the stage checkpoints. Returns a summary
    ``{"name", "status": skipped|done|failed, "action", "error"}``; never raises for a failed
    subprocess (the error names the log file). ``node``: the Ray node that ran it, kept in the
    run's marker."""
    report = status or (lambda name, state: None)
    run_dir, log = Path(task.run_dir), Path(task.log_path)
    result: dict[str, Any] = {"name": task.name, "variant": task.variant, "seed": task.seed}
    if run_is_finished(task):
        report(task.name, "skipped")
        return {**result, "status": "skipped", "action": "finished earlier"}

    iteration = trained_iteration(run_dir)
    if iteration is not None and (run_dir / "config.yaml").is_file():
        if iteration < task.num_iterations:
            action = f"resumed at iteration {iteration}"
            report(task.name, "training")
            args = ["train", "--resume", "--run-dir", str(run_dir)]
            args += ["--total-steps", str(task.total_steps), "--no-progress"]
            code = _cli(args, log)
        else:
            action, code = "evaluated (training was finished)", 0
    else:
        started = run_dir.is_dir() and any(p.name != LOCK for p in run_dir.iterdir())
        if started:  # but no usable checkpoint: start again
            try:  # what train wrote there, only if it holds nothing else (its lock stays)
                clear_project_dir(run_dir, RUN, keep=(LOCK,))
            except FileExistsError as error:
                report(task.name, "failed")
                return {**result, "status": "failed", "action": "not started", "error": str(error)}
        action = "trained"
        report(task.name, "training")
        code = _cli(["train", *task.train_args], log)
    if code != 0:
        report(task.name, "failed")
        return {
            **result,
            "status": "failed",
            "action": action,
            "error": f"cpg-actor train exited with {code}; see {log}",
        }

    report(task.name, "evaluating")
    try:
        stages = evaluate_stages(task, log)
    except (RuntimeError, ValueError) as error:
        report(task.name, "failed")
        return {**result, "status": "failed", "action": action, "error": str(error)}
    marker = {
        "status": "done",
        "total_steps": task.total_steps,
        "num_iterations": task.num_iterations,
        "commit": git_commit(),  # the code that finished the run
        "stages": stages,
    }
    if node is not None:
        marker["node"] = node
    atomic_write_text(json.dumps(marker, indent=2) + "\n", run_dir / MARKER)
    report(task.name, "done")
    return {**result, "status": "done", "action": action}


def evaluate_stages(task: RunTask, log: Path) -> list[dict[str, Any]]:
    """Deterministic ``cpg-actor eval`` at the checkpoints nearest to each stage fraction;
    traces in ``RUN_DIR/eval/stageK/traces.npz``, the choice in ``RUN_DIR/eval/stages.json``."""
    run_dir = Path(task.run_dir)
    chosen = select_stage_checkpoints(
        list_checkpoints(run_dir), task.num_iterations, task.stage_fractions
    )
    previous = _read_stages(run_dir)
    stages: list[dict[str, Any]] = []
    for k, (fraction, iteration, checkpoint) in enumerate(chosen):
        output = run_dir / "eval" / f"stage{k}" / "traces.npz"
        refuse_linked_folders(run_dir / "eval", output.parent)  # the run's own folders
        entry = {
            "stage": k,
            "fraction": fraction,
            "iteration": iteration,
            "checkpoint": str(checkpoint.relative_to(run_dir)),
            "traces": str(output.relative_to(run_dir)),
        }
        reuse = k < len(previous) and previous[k].get("iteration") == iteration
        same = [stage for stage in stages if stage["iteration"] == iteration]
        if output.is_file() and reuse:
            pass
        elif same:  # two stages on one checkpoint (a short run): the same traces
            output.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(run_dir / same[0]["traces"], output)
        else:
            args = ["eval", str(run_dir), "--checkpoint", str(checkpoint)]
            args += ["--output", str(output), "--episodes", str(task.eval_episodes), "--overwrite"]
            code = _cli(args, log)
            if code != 0:
                raise RuntimeError(f"cpg-actor eval exited with {code}; see {log}")
        stages.append(entry)
        atomic_write_text(json.dumps(stages, indent=2) + "\n", run_dir / "eval" / STAGES_FILE)
    return stages


def _read_stages(run_dir: Path) -> list[dict[str, Any]]:
    path = run_dir / "eval" / STAGES_FILE
    try:
        return json.loads(path.read_text()) if path.is_file() else []
    except ValueError:
        return []


# -- progress ---------------------------------------------------------------------------------
def read_progress(run_dir: Path) -> tuple[int, float | None]:
    """``(global_step, SPS)`` of the last row of ``RUN_DIR/metrics.jsonl`` (0, None if none)."""
    path = Path(run_dir) / "metrics.jsonl"
    if not path.is_file():
        return 0, None
    try:
        with open(path, "rb") as f:
            f.seek(0, os.SEEK_END)
            size = f.tell()
            f.seek(max(0, size - 16384))
            lines = f.read().decode(errors="replace").splitlines()
    except OSError:
        return 0, None
    for line in reversed(lines):
        try:
            row = json.loads(line)
        except ValueError:
            continue
        return int(row.get("global_step", 0)), row.get("charts/SPS")
    return 0, None


class Progress:
    """Per-run state (pending, training, evaluating, done, skipped, failed), steps and SPS read
    from each run's ``metrics.jsonl``, and an overall ETA from the throughput of this session.
    Shown as a rich live table on a terminal, otherwise as periodic blocks of lines."""

    def __init__(self, tasks: list[RunTask], interval: float, live: bool) -> None:
        self.tasks = tasks
        self.interval = interval
        self.state = {task.name: "pending" for task in tasks}
        self.lock = threading.Lock()
        self.start = time.monotonic()
        self.start_steps = {task.name: read_progress(Path(task.run_dir))[0] for task in tasks}
        self.live = None
        if live:
            from rich.live import Live

            self.live = Live(self.table(), refresh_per_second=1, transient=False)

    def set(self, name: str, state: str) -> None:
        with self.lock:
            self.state[name] = state
        if self.live is None and state in ("done", "skipped", "failed", "training"):
            print(f"[reproduce] {name}: {state}", flush=True)

    def snapshot(self) -> tuple[list[tuple[RunTask, str, int, float | None]], str]:
        rows, done_total, gained = [], 0, 0
        for task in self.tasks:
            steps, sps = read_progress(Path(task.run_dir))
            with self.lock:
                state = self.state[task.name]
            if state in ("done", "skipped"):
                steps = task.planned_steps
            rows.append((task, state, steps, sps))
            done_total += min(steps, task.planned_steps)
            gained += max(0, steps - self.start_steps[task.name])
        total = sum(task.planned_steps for task in self.tasks)
        elapsed = time.monotonic() - self.start
        rate = gained / elapsed if elapsed > 0 else 0.0
        eta = _duration((total - done_total) / rate) if rate > 0 else "-"
        overall = (
            f"overall {done_total:,}/{total:,} steps ({100 * done_total / total:.1f}%), "
            f"{rate:,.0f} steps/s, elapsed {_duration(elapsed)}, ETA {eta}"
        )
        return rows, overall

    def lines(self) -> list[str]:
        rows, overall = self.snapshot()
        out = [
            f"  {task.name:<32} {state:<10} {steps:>12,}/{task.planned_steps:,} steps"
            + (f"  {sps:,.0f} SPS" if sps and state in ("training", "submitted") else "")
            for task, state, steps, sps in rows
        ]
        return [*out, "  " + overall]

    def table(self):
        from rich.table import Table

        rows, overall = self.snapshot()
        table = Table(title="cpg-actor reproduce", caption=overall)
        for column in ("run", "state", "steps", "%", "SPS"):
            table.add_column(column, justify="right" if column != "run" else "left")
        for task, state, steps, sps in rows:
            table.add_row(
                task.name,
                state,
                f"{steps:,}/{task.planned_steps:,}",
                f"{100 * min(steps, task.planned_steps) / task.planned_steps:.0f}",
                f"{sps:,.0f}" if sps and state in ("training", "submitted") else "-",
            )
        return table

    def watch(self, finished: Callable[[], bool]) -> None:
        """Refresh until ``finished()``; call from the main thread."""
        if self.live is not None:
            with self.live:
                while not finished():
                    self.live.update(self.table())
                    time.sleep(0.5)
                self.live.update(self.table())
            return
        last = time.monotonic()
        while not finished():
            time.sleep(0.2)
            if time.monotonic() - last >= self.interval:
                last = time.monotonic()
                print("[reproduce] progress\n" + "\n".join(self.lines()), flush=True)
        print("[reproduce] " + self.lines()[-1].strip(), flush=True)


def _duration(seconds: float) -> str:
    seconds = int(round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}"


# -- schedulers -------------------------------------------------------------------------------
def run_local(tasks: list[RunTask], workers: int, progress: Progress) -> list[dict[str, Any]]:
    """Run the tasks on ``workers`` threads, each driving one subprocess at a time."""
    results: list[dict[str, Any]] = []
    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        futures = [pool.submit(run_one, task, progress.set) for task in tasks]
        try:
            progress.watch(lambda: all(f.done() for f in futures))
        except KeyboardInterrupt:  # the running subprocesses got SIGINT too and checkpoint
            STOP.set()
            for future in futures:
                future.cancel()
            raise
        for task, future in zip(tasks, futures, strict=True):
            try:
                results.append(future.result())
            except Exception as error:  # a bug, not a failed subprocess: keep the others
                results.append(
                    {
                        "name": task.name,
                        "variant": task.variant,
                        "seed": task.seed,
                        "status": "failed",
                        "action": "-",
                        "error": repr(error),
                    }
                )
    return results


def import_ray():
    try:
        import ray
    except ImportError:
        raise ValueError(
            "--ray needs Ray, which is not installed: pip install cpg-actor[ray]"
        ) from None
    return ray


# -- Ray: connecting ----------------------------------------------------------------------------
# seconds the head's address has to accept a TCP connection: an address nobody answers made
# ray.init wait for many minutes
CONNECT_TIMEOUT = 10.0
TOKEN_HELP = (
    "on the head, `ray get-auth-token` prints the cluster's token; here set RAY_AUTH_MODE=token "
    "and RAY_AUTH_TOKEN=<token> (or RAY_AUTH_TOKEN_PATH=<file holding it>; default "
    "~/.ray/auth_token)"
)


def _host_port(address: str) -> tuple[str, int] | None:
    """``(host, port)`` of ``host:port``, ``ray://host:port`` or ``[v6]:port`` (None if none)."""
    text = address.removeprefix("ray://")
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit():
        return None
    return host.strip("[]"), int(port)


def check_reachable(address: str, timeout: float = CONNECT_TIMEOUT) -> None:
    """Raise ConnectionError (one line) unless the head at ``address`` accepts a TCP
    connection within ``timeout`` seconds. "auto" is checked as ``RAY_ADDRESS`` when that is
    set; otherwise Ray looks for a cluster on this machine itself."""
    if address == "auto":
        address = os.environ.get("RAY_ADDRESS") or "auto"
    target = _host_port(address)
    if target is None:
        return
    try:
        socket.create_connection(target, timeout=timeout).close()
    except OSError as error:
        reason = "no answer" if isinstance(error, TimeoutError) else error.strerror or str(error)
        raise ConnectionError(
            f"cannot reach the Ray head at {address} within {timeout:g} s ({reason}); check the "
            f"address (`ray start --head` prints it), that the head runs and that port "
            f"{target[1]} is open to this machine"
        ) from None


def _token_state() -> str:
    """What this process would authenticate with, for an error message."""
    if os.environ.get("RAY_AUTH_MODE", "").lower() != "token":
        return "RAY_AUTH_MODE is not 'token' here"
    path = os.environ.get("RAY_AUTH_TOKEN_PATH")
    if os.environ.get("RAY_AUTH_TOKEN"):
        return "RAY_AUTH_TOKEN does not match the cluster's token"
    if path:
        if not Path(path).is_file():
            return f"RAY_AUTH_TOKEN_PATH names {path}, which does not exist"
        return f"the token in RAY_AUTH_TOKEN_PATH={path} does not match the cluster's"
    if not (Path.home() / ".ray" / "auth_token").is_file():
        return "no token is set (RAY_AUTH_TOKEN, RAY_AUTH_TOKEN_PATH, ~/.ray/auth_token)"
    return "the token in ~/.ray/auth_token does not match the cluster's"


def _connect_error(address: str, error: BaseException) -> str:
    """One line for a failed ``ray.init(address=...)``: a missing or wrong token, or else."""
    chain, seen = [], error
    while seen is not None and len(chain) < 5:
        chain.append(f"{type(seen).__name__}: {seen}")
        seen = seen.__cause__ or seen.__context__
    text = " ".join(chain)
    if "InvalidAuthToken" in text or "AuthenticationError" in text:
        return (
            f"the Ray cluster at {address} refused this process's authentication token "
            f"({_token_state()}); {TOKEN_HELP}"
        )
    first = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
    return (
        f"cannot connect to the Ray cluster at {address}: {first}; is Ray running there "
        f"(`ray status --address {address}` on the head)?"
    )


def connect_ray(address: str, local_gpus: int | None = None) -> None:
    """``ray.init`` for ``--ray ADDRESS`` ("local": a local instance with ``local_gpus`` GPUs
    declared, None: the GPUs it finds). Raises ConnectionError with one line when the address
    does not answer or refuses this process's token."""
    ray = import_ray()
    if address == "local":
        ray.init(include_dashboard=False, log_to_driver=False, num_gpus=local_gpus)
        return
    check_reachable(address)
    try:
        ray.init(address=address, log_to_driver=False)
    except Exception as error:  # Ray raises ConnectionError, RuntimeError, AuthenticationError
        raise ConnectionError(_connect_error(address, error)) from None


def disconnect_ray() -> None:
    try:
        import ray
    except ImportError:
        return
    if ray.is_initialized():
        ray.shutdown()


# -- Ray: moving run directories ------------------------------------------------------------
# how a Ray task's run reaches OUT: "shared": written there directly (the node sees OUT);
# "return": trained in a temporary directory on its node, returned to the head packed;
# "auto": shared where the node sees OUT, return elsewhere
RAY_RESULTS = ("auto", "shared", "return")
RETURNED_LOG = "run.log"  # the run's log, next to "run/", in a packed run


def pack_run(run_dir: Path, log_path: Path) -> bytes | None:
    """The run directory (without its lock file) and its log as a gzipped tar, None if
    neither exists."""
    run_dir, log_path = Path(run_dir), Path(log_path)
    if not run_dir.is_dir() and not log_path.is_file():
        return None
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz", compresslevel=1) as tar:
        if run_dir.is_dir():
            tar.add(run_dir, "run", filter=lambda m: None if m.name == f"run/{LOCK_NAME}" else m)
        if log_path.is_file():
            tar.add(log_path, RETURNED_LOG)
    return buffer.getvalue()


def _stamp(path: Path) -> tuple[int, int] | None:
    """``(size, mtime_ns)`` of ``path`` (a link's own), None if there is nothing there."""
    try:
        stat = path.lstat()
    except FileNotFoundError:
        return None
    return stat.st_size, stat.st_mtime_ns


def run_files(run_dir: Path) -> dict[str, tuple[int, int] | None]:
    """``{relative path: (size, mtime_ns)}`` of the files :func:`pack_run` packs from
    ``run_dir`` (links listed, not followed)."""
    found = {}
    for folder, _, names in os.walk(run_dir):
        for name in names:
            relative = (Path(folder) / name).relative_to(run_dir).as_posix()
            if relative != LOCK_NAME:
                found[relative] = _stamp(Path(folder) / name)
    return found


def unpack_run(
    data: bytes, run_dir: Path, log_path: Path, sent: dict[str, Any] | None = None
) -> None:
    """Merge what :func:`pack_run` packed into ``run_dir`` and ``log_path``: each of its files
    replaces its namesake (a rename); a file of ``sent`` (:func:`run_files` of what was packed
    for the run) that the run removed is removed if unchanged since; any other file (one added
    meanwhile) is kept. Folders that are links are refused, never written through."""
    run_dir, log_path = Path(run_dir), Path(log_path)
    run_dir.parent.mkdir(parents=True, exist_ok=True)
    incoming = Path(tempfile.mkdtemp(prefix=f".{run_dir.name}.incoming-", dir=run_dir.parent))
    try:
        with tarfile.open(fileobj=io.BytesIO(data), mode="r:gz") as tar:
            if hasattr(tarfile, "data_filter"):  # refuses links and paths out of `incoming`
                tar.extractall(incoming, filter="data")
            else:
                tar.extractall(incoming)
        returned = incoming / "run"
        received = run_files(returned) if returned.is_dir() else {}
        for relative in received:
            target = run_dir / relative
            for folder in (target.parent, *target.parent.parents):
                refuse_link(folder)
                if folder == run_dir:
                    break
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(returned / relative, target)
        for relative, stamp in (sent or {}).items():
            target = run_dir / relative
            if relative not in received and stamp is not None and _stamp(target) == stamp:
                target.unlink()  # the run removed it (a checkpoint of an earlier attempt)
        if (incoming / RETURNED_LOG).is_file():
            log_path.parent.mkdir(parents=True, exist_ok=True)
            shutil.move(incoming / RETURNED_LOG, log_path)
    finally:
        shutil.rmtree(incoming, ignore_errors=True)


def _sees(probe: tuple[str, str] | None) -> bool:
    """This node reads the head's probe file: it sees OUT at the head's path."""
    if probe is None:
        return False
    try:
        return Path(probe[0]).read_text() == probe[1]
    except OSError:
        return False


def _moved(task: RunTask, run_dir: Path, log: Path) -> RunTask:
    """``task`` with its run directory and log at ``run_dir`` and ``log``."""
    args = list(task.train_args)
    args[args.index("--run-dir") + 1] = str(run_dir)
    return dataclasses.replace(
        task, run_dir=str(run_dir), log_path=str(log), train_args=tuple(args)
    )


def _in_scratch(task: RunTask, scratch: Path) -> RunTask:
    """``task`` with its run directory and log in ``scratch``."""
    return _moved(task, scratch / "run", scratch / RETURNED_LOG)


def _absolute(task: RunTask) -> RunTask:
    """``task`` with absolute paths: a Ray worker's working directory is not the head's."""
    return _moved(task, Path(task.run_dir).resolve(), Path(task.log_path).resolve())


def run_one_on_ray(
    task: RunTask,
    results: str = "auto",
    probe: tuple[str, str] | None = None,
    files: bytes | None = None,
) -> dict[str, Any]:
    """:func:`run_one` as a Ray task, with the node that ran it (``node``: Ray's node id, its
    IP and host name) and the resources Ray gave it (``resources``: CPU, and GPU shares; Ray
    sets ``CUDA_VISIBLE_DEVICES`` for the run's subprocess). Where the run is not written into
    OUT (see ``RAY_RESULTS``), it starts from ``files`` (the head's copy, packed) and
    ``files`` in the result is the run afterwards, packed, for the head to unpack."""
    import ray

    node = {
        "id": ray.get_runtime_context().get_node_id(),
        "ip": ray.util.get_node_ip_address(),
        "hostname": socket.gethostname(),
    }
    if probe is None:  # nothing to check against: as asked
        shared = results == "shared"
    else:
        shared = results != "return" and _sees(probe)
    if results == "shared" and not shared:
        raise RuntimeError(
            f"node {node['hostname']} ({node['ip']}) does not see the results directory "
            f"{Path(probe[0]).parent} of the head: it is not on a file system shared with this "
            "node; use --ray-results auto or return"
        )
    if shared:
        result = run_one(task, node={**node, "files": "shared"})
    else:
        with tempfile.TemporaryDirectory(prefix="cpg-actor-run-") as scratch:
            local = _in_scratch(task, Path(scratch))
            if files is not None:
                unpack_run(files, Path(local.run_dir), Path(local.log_path))
            result = run_one(local, node={**node, "files": "returned"})
            result["files"] = pack_run(Path(local.run_dir), Path(local.log_path))
            if result.get("error"):  # name the head's log, where it will be
                result["error"] = result["error"].replace(local.log_path, task.log_path)
    result["node"] = node
    result["resources"] = dict(ray.get_runtime_context().get_assigned_resources())
    return result


# -- Ray: scheduling ----------------------------------------------------------------------------
# a run whose worker or node dies is started again (on another node if its node is gone), this
# many times; it resumes from its last checkpoint where OUT is shared, and starts from the
# files the head sent it otherwise
RAY_RETRIES = 2


def _failed(task: RunTask, error: str) -> dict[str, Any]:
    return {
        "name": task.name,
        "variant": task.variant,
        "seed": task.seed,
        "status": "failed",
        "action": "-",
        "error": error,
    }


def run_ray(
    tasks: list[RunTask],
    address: str,
    progress: Progress,
    gpus_per_run: float = 0.0,
    local_gpus: int | None = None,
    results: str = "auto",
    out: Path | None = None,
) -> list[dict[str, Any]]:
    """One Ray task per unfinished run on the cluster at ``address`` (connected to unless
    already: :func:`connect_ray`), each asking for one CPU and ``gpus_per_run`` of a GPU (e.g.
    0.2: five runs share a GPU; Ray places them and sets ``CUDA_VISIBLE_DEVICES``). ``results``
    (``RAY_RESULTS``) says how runs reach ``out``, the results directory on this machine."""
    if not gpus_per_run >= 0:
        raise ValueError(f"gpus_per_run must be >= 0, got {gpus_per_run!r}")
    if results not in RAY_RESULTS:
        raise ValueError(f"--ray-results must be one of {', '.join(RAY_RESULTS)}, got {results!r}")
    ray = import_ray()
    if not ray.is_initialized():
        connect_ray(address, local_gpus)
    probe_path = None
    try:
        probe = None
        if results != "return" and out is not None:
            token = secrets.token_hex(16)
            probe_path = Path(out).resolve() / f".ray-probe-{token[:8]}"
            probe_path.write_text(token)
            probe = (str(probe_path), token)
        options = {"num_cpus": 1, "max_retries": RAY_RETRIES}
        if gpus_per_run > 0:
            options["num_gpus"] = gpus_per_run
        remote = ray.remote(**options)(run_one_on_ray)
        collected: list[dict[str, Any]] = []
        pending = {}
        sent: dict[str, dict[str, Any]] = {}  # what each returned run started from
        for task in tasks:
            if run_is_finished(task):
                progress.set(task.name, "skipped")
                collected.append(
                    {"name": task.name, "variant": task.variant, "seed": task.seed,
                     "status": "skipped", "action": "finished earlier"}
                )  # fmt: skip
                continue
            files = None
            if results != "shared":
                sent[task.name] = run_files(Path(task.run_dir))
                files = pack_run(Path(task.run_dir), Path(task.log_path))
            pending[remote.remote(_absolute(task), results, probe, files)] = task
            progress.set(task.name, "submitted")

        def finished() -> bool:
            if pending:
                ready, _ = ray.wait(list(pending), num_returns=len(pending), timeout=0)
                for ref in ready:
                    task = pending.pop(ref)
                    try:
                        result = ray.get(ref)
                        files = result.pop("files", None)
                        if files is not None:
                            unpack_run(files, Path(task.run_dir), Path(task.log_path),
                                       sent.get(task.name))  # fmt: skip
                    except Exception as error:  # the task raised, died RAY_RETRIES + 1 times
                        result = _failed(task, _one_line(error))
                    progress.set(task.name, result["status"])
                    collected.append(result)
            return not pending

        progress.watch(finished)
    finally:
        if probe_path is not None:
            probe_path.unlink(missing_ok=True)
        ray.shutdown()
    order = {task.name: i for i, task in enumerate(tasks)}
    return sorted(collected, key=lambda r: order[r["name"]])


def _one_line(error: BaseException) -> str:
    """A task's error in one line: Ray wraps an exception raised in a task with the remote
    traceback; its last line is the exception itself."""
    cause = getattr(error, "cause", None)
    if isinstance(cause, BaseException):
        return f"{type(cause).__name__}: {cause}"
    lines = [line for line in str(error).strip().splitlines() if line.strip()]
    return lines[-1].strip() if lines else repr(error)
