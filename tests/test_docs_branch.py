"""docs/results/trio-20M/branch.py: a run branched from one of its checkpoints with a changed
config value, the checkpoint read as `cpg-actor train --resume` reads it (never code); bad
input is one line and leaves no OUT behind."""

import os
import subprocess
import sys
from pathlib import Path

import pytest
import torch
import yaml

from cpg_actor.files import RUN, write_marker
from cpg_actor.training.checkpoint import load_checkpoint

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "docs" / "results" / "trio-20M" / "branch.py"


def run(*args) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True,
                          text=True, env=env, timeout=300)  # fmt: skip


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    from tiny import trained_run  # tests/tiny.py

    return trained_run(tmp_path_factory.mktemp("run") / "seed0", "mlp", checkpoint_interval=1)


def test_a_branch_carries_the_change_in_its_config_and_checkpoint(trained, tmp_path):
    out = tmp_path / "branch"
    done = run(trained, 1, out, "ppo.learning_rate=3e-5")
    assert done.returncode == 0, done.stderr
    assert yaml.safe_load((out / "config.yaml").read_text())["ppo"]["learning_rate"] == 3e-5
    for name in ("iter_000001.pt", "last.pt"):
        checkpoint = load_checkpoint(out / "checkpoints" / name)
        assert checkpoint["config"]["ppo"]["learning_rate"] == 3e-5
        assert checkpoint["iteration"] == 1
    assert (out / "metrics.jsonl").read_bytes() == (trained / "metrics.jsonl").read_bytes()


class _Payload:
    """Pickled as a call to ``open(path, "w")``: what unpickling it runs makes the file."""

    def __init__(self, path: Path) -> None:
        self.path = str(path)

    def __reduce__(self):
        return (open, (self.path, "w"))


def test_a_checkpoint_that_carries_code_is_refused_without_running_it(trained, tmp_path):
    source = tmp_path / "run"
    (source / "checkpoints").mkdir(parents=True)
    for name in ("config.yaml", "metrics.jsonl"):
        (source / name).write_bytes((trained / name).read_bytes())
    write_marker(source, RUN)  # a run directory as `cpg-actor train` leaves it
    ran = tmp_path / "the payload ran"
    checkpoint = torch.load(trained / "checkpoints" / "iter_000001.pt", weights_only=True)
    checkpoint["payload"] = _Payload(ran)
    torch.save(checkpoint, source / "checkpoints" / "iter_000001.pt")
    done = run(source, 1, tmp_path / "branch", "ppo.learning_rate=0.001")
    assert not ran.exists()  # weights_only: the checkpoint's code never runs
    assert done.returncode != 0 and len(done.stderr.splitlines()) == 1, done.stderr
    assert "is corrupt or not a cpg-actor checkpoint" in done.stderr
    assert not (tmp_path / "branch").exists()


def test_bad_input_is_one_line_and_leaves_no_branch(trained, tmp_path):
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("mine\n")
    truncated = tmp_path / "truncated"
    (truncated / "checkpoints").mkdir(parents=True)
    for name in ("config.yaml", "metrics.jsonl"):
        (truncated / name).write_bytes((trained / name).read_bytes())
    packed = (trained / "checkpoints" / "iter_000001.pt").read_bytes()
    (truncated / "checkpoints" / "iter_000001.pt").write_bytes(packed[: len(packed) // 2])
    cases = [
        ((trained, 1, tmp_path / "b", "no_such_key=1"), "no_such_key: "),
        ((trained, 1, tmp_path / "b", "ppo.no_such_key=1"), "has no such key"),
        ((trained, 99, tmp_path / "b", "seed=1"), "iter_000099.pt does not exist"),
        ((trained, "one", tmp_path / "b", "seed=1"), "usage: branch.py"),
        ((trained, 1, tmp_path / "b", "seed"), "usage: branch.py"),
        ((trained, 1, tmp_path / "mine", "seed=1"), "mine exists"),
        ((tmp_path / "missing", 1, tmp_path / "b", "seed=1"), "not a run directory"),
        ((truncated, 1, tmp_path / "b", "seed=1"), "is corrupt or not a cpg-actor checkpoint"),
    ]
    for args, message in cases:
        done = run(*args)
        assert done.returncode != 0 and len(done.stderr.splitlines()) == 1, (args, done.stderr)
        assert message in done.stderr, (args, done.stderr)
        assert not (tmp_path / "b").exists(), args
    assert sorted(p.name for p in (tmp_path / "mine").iterdir()) == ["notes.txt"]
