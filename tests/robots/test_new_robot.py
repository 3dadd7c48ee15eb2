"""A robot added from outside the package (``docs/extending.md``, "A new robot from an existing
one"): the doc's two files, written as they stand in a temporary package, register a copy of
the Go1 that trains from the command line with the Go1's recipe."""

from __future__ import annotations

import re
import runpy
import sys
from pathlib import Path

import pytest
import yaml

from cpg_actor.robots.registry import ROBOTS

DOC = Path(__file__).resolve().parents[2] / "docs" / "extending.md"


@pytest.fixture
def registry_kept(monkeypatch):
    """The registry and the imported modules as they were, after the test."""
    robots = dict(ROBOTS)
    yield
    ROBOTS.clear()
    ROBOTS.update(robots)
    for name in [name for name in sys.modules if name.split(".")[0] == "my_robots"]:
        del sys.modules[name]


def doc_files() -> dict[str, str]:
    """The doc's Python blocks that open with ``# PATH: ...``, by that path."""
    blocks = re.findall(r"```python\n# ([\w/]+\.py)\b(.*?)```", DOC.read_text(), flags=re.S)
    return {path: f"# {path}{rest}" for path, rest in blocks}


def test_a_copy_of_a_robot_registered_outside_the_package_trains(
    tmp_path, monkeypatch, capsys, registry_kept
):
    files = doc_files()
    assert set(files) == {"my_robots/go1_stiff.py", "my_cli.py"}
    for path, text in files.items():
        (tmp_path / path).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / path).write_text(text)
    monkeypatch.syspath_prepend(str(tmp_path))
    run = tmp_path / "run"
    argv = ["train", "--robot", "go1-stiff", "--total-steps", "256", "--num-envs", "2",
            "--run-dir", str(run), "--no-progress", "--set", "ppo.num_steps=16",
            "--set", "ppo.compile=false", "--set", "eval_interval=0",
            "--set", "env.episode_seconds=0.2"]  # fmt: skip
    monkeypatch.setattr(sys, "argv", ["my_cli.py", *argv])
    with pytest.raises(SystemExit) as done:
        runpy.run_path(str(tmp_path / "my_cli.py"), run_name="__main__")
    assert done.value.code == 0, capsys.readouterr().err
    assert (run / "checkpoints" / "last.pt").is_file()
    config = yaml.safe_load((run / "config.yaml").read_text())
    # its own config's numbers, and the Go1's recipe with its agents' tuned settings
    assert (config["robot"], config["env"]["kp"], config["preset"]) == ("go1-stiff", 150.0,
                                                                         "throughput")  # fmt: skip
    assert config["agent_config"]["cpg_layout"] == "leg"
    assert ROBOTS["go1-stiff"].agent_defaults == ROBOTS["go1"].agent_defaults
