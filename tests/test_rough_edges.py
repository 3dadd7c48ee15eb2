"""Rough edges of the command line: a size that would exhaust memory or time, a value outside
what the simulation means, a typo; each is one line saying what is wrong and what is accepted,
given before anything is built or written."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cpg_actor.cli import main

TINY = ["--total-steps", "16", "--num-envs", "2", "--set", "ppo.num_steps=8", "--set",
        "ppo.num_minibatches=2", "--set", "ppo.compile=false", "--no-progress"]  # fmt: skip


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> Path:
    """A finished tiny run (one iteration of 16 steps); copy it before changing it."""
    run_dir = tmp_path_factory.mktemp("trained") / "run"
    assert main(["train", "--run-dir", str(run_dir), *TINY]) == 0
    return run_dir


def copy_of(run_dir: Path, tmp_path: Path) -> Path:
    shutil.copytree(run_dir, tmp_path / run_dir.name)
    return tmp_path / run_dir.name


# -- upper bounds and absurd values ------------------------------------------------------------
@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--set", "env.episode_steps=1000000000"], "at most 100,000 are accepted"),
        (["--robot", "anymal", "--set", "env.episode_seconds=1e9"], "at most 100,000"),
        (["--set", "env.perturbation.latency=1e9"], "latency <= 50"),
        (["--set", "env.perturbation.motor_strength=1e9"], "motor_strength <= 10"),
        (["--set", "env.perturbation.friction=1e308"], "friction <= 10"),
        (["--set", "env.randomize.payload=[0,1e9]"], "low <= high <= 100"),
        # the hopper's episode is 5 s: a push 6-7 s in never comes
        (["--set", "env.perturbation.push=1", "--set", "env.perturbation.push_time=[6,7]"],
         "push_time starts at 6 s, at or after the end of the episode (5 s)"),
    ],
)  # fmt: skip
def test_a_size_or_value_out_of_range_is_one_line_and_creates_nothing(
    tmp_path, capsys, argv, message
):
    run_dir = tmp_path / "run"
    assert main(["train", "--run-dir", str(run_dir), *argv, *TINY]) == 2
    assert message in one_line(capsys)
    assert not run_dir.exists()


def test_a_push_window_that_starts_within_the_episode_pushes_every_episode():
    from cpg_actor.robots.common.perturbation import EpisodeDraws, Perturbation
    from cpg_actor.robots.hopper.config import HopperConfig

    HopperConfig(perturbation=Perturbation(push=1.0, push_time=(1.0, 4.9)))
    # a window past the end: every episode is still pushed, by its last step
    config = HopperConfig(perturbation=Perturbation(push=1.0, push_time=(4.0, 9.0)))
    assert EpisodeDraws(config, 1, [0.0]).window == (400, 499)
    HopperConfig(episode_steps=100_000, perturbation=Perturbation(motor_strength=10.0))


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["export", "RUN", "--batch", "100000000"], "--batch must be an integer from 1 to 65,536"),
        (["eval", "RUN", "--episodes", "100000000"], "--episodes must be an integer from 1 to"),
        (["robustness", "RUN", "--out", "OUT", "--episodes", "0"], "--episodes must be an integer"),
        (["gaits", "--robots", "100000000", "--out", "OUT"], "--robots must be an integer from 1"),
    ],
)
def test_a_count_too_large_is_one_line(tmp_path, capsys, argv, message):
    argv = [str(tmp_path / word) if word in ("RUN", "OUT") else word for word in argv]
    (tmp_path / "RUN").mkdir()
    (tmp_path / "RUN" / "config.yaml").write_text("agent: cpg-actor\n")
    assert main(argv) == 2
    assert message in one_line(capsys)
    assert not (tmp_path / "OUT").exists()


def test_gaits_errors_name_the_command_not_its_forward_command(tmp_path, capsys):
    assert main(["gaits", "--seconds", "-1", "--command", "0.7", "--out", str(tmp_path)]) == 2
    assert one_line(capsys).startswith("cpg-actor gaits: error: --seconds must be a positive")


# -- a trained run -----------------------------------------------------------------------------
def test_a_video_format_eval_cannot_write_is_refused_before_evaluating(tmp_path, capsys, trained):
    run_dir = copy_of(trained, tmp_path)
    capsys.readouterr()
    assert main(["eval", str(run_dir), "--video", str(tmp_path / "x.avi")]) == 2
    err = one_line(capsys)
    assert not (run_dir / "eval").exists()  # nothing evaluated, nothing replaced
    assert "--video must end in .mp4 or .gif, got" in err


def test_resuming_a_finished_run_says_so_and_changes_nothing(tmp_path, capsys, trained):
    """The README's `--resume` line after the run it continues has finished."""
    run_dir = copy_of(trained, tmp_path)

    def files() -> dict[Path, bytes]:  # but the run's lock, taken again by each command
        return {p: p.read_bytes() for p in run_dir.rglob("*") if p.is_file() and p.name != ".lock"}

    before = files()
    capsys.readouterr()
    assert main(["train", "--run-dir", str(run_dir), "--resume"]) == 0
    assert "is finished at iteration 1 (16 steps); nothing to continue" in capsys.readouterr().out
    assert files() == before


def test_robustness_refuses_a_run_given_twice(tmp_path, capsys, trained):
    run_dir = copy_of(trained, tmp_path)
    again = tmp_path / "." / run_dir.name  # the same run, written another way
    capsys.readouterr()
    argv = ["robustness", str(run_dir), str(run_dir), str(again), "--out", str(tmp_path / "out")]
    assert main(argv) == 2
    assert "the same run given twice; give each run once" in one_line(capsys)
    assert not (tmp_path / "out").exists()


def test_robustness_refuses_an_out_that_is_a_file_before_the_suite(tmp_path, capsys, trained):
    out = tmp_path / "report.md"
    out.write_text("mine\n")
    capsys.readouterr()
    assert main(["robustness", str(trained), "--out", str(out), "--episodes", "1"]) == 2
    printed = capsys.readouterr()
    assert printed.out == ""  # no run evaluated
    assert printed.err.count("\n") == 1
    assert f"--out {out} is a file, not a directory; give a directory path" in printed.err
    assert out.read_text() == "mine\n"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("seed: 1\nppo:\n  learning_rate: 0.001\n  learning_rate: 0.01\n",
         "at line 4, column 3: duplicate key 'learning_rate' (give each key once)"),
        ("seed: 1\nseed: 2\n", "at line 2, column 1: duplicate key 'seed'"),
        # still the safe loader: a tag that would build an object is refused, in one line
        ("x: !!python/object/apply:os.system ['true']\n", "could not determine a constructor"),
    ],
)  # fmt: skip
def test_a_config_file_with_a_key_given_twice_is_refused_naming_it(tmp_path, capsys, text, message):
    path = tmp_path / "config.yaml"
    path.write_text(text)
    run_dir = tmp_path / "run"
    assert main(["train", "--config", str(path), "--run-dir", str(run_dir), *TINY]) == 2
    assert f"{path} is not valid YAML" in (err := one_line(capsys)) and message in err
    assert not run_dir.exists()


FULL_DISK = """
import errno, sys
from tensorboard.summary.writer import record_writer

def full(self, data):  # every TensorBoard event write finds the disk full
    raise OSError(errno.ENOSPC, "No space left on device")

record_writer.RecordWriter.write = full
from cpg_actor.cli import main
sys.exit(main(sys.argv[1:]))
"""


def test_a_full_disk_under_tensorboard_is_one_line_naming_its_folder(tmp_path):
    """TensorBoard writes in a thread of its own; its error is reported once, in one line."""
    run_dir = tmp_path / "run"
    argv = ["train", "--run-dir", str(run_dir), *TINY]
    done = subprocess.run([sys.executable, "-c", FULL_DISK, *argv], capture_output=True,
                          text=True, timeout=300)  # fmt: skip
    assert done.returncode == 1
    assert done.stderr == (
        f"cpg-actor train: error: no space left on device while writing {run_dir / 'tensorboard'}\n"
    )


# -- reproduce's and sweep's runs die with them ------------------------------------------------
PARENT = """
import sys
from pathlib import Path
from cpg_actor_studies.reproduction import execute

# a run as reproduce and sweep start one, long enough to outlive its parent
execute._cli(["train", "--run-dir", sys.argv[1], "--total-steps", "100M", "--num-envs", "2",
              "--set", "ppo.compile=false", "--no-progress"], Path(sys.argv[2]))
"""


def _children(pid: int) -> list[int]:
    """The processes whose parent is ``pid`` (Linux's /proc)."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:  # it ended meanwhile
            continue
        if int(fields[1]) == pid:
            found.append(int(stat.parent.name))
    return found


def _alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie, dead but not yet reaped, does not)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
def test_a_run_dies_with_the_reproduce_or_sweep_that_started_it(tmp_path):
    import signal
    import time

    log = tmp_path / "run.log"
    parent = subprocess.Popen([sys.executable, "-c", PARENT, str(tmp_path / "run"), str(log)])
    child = None
    try:
        for _ in range(1200):  # polled until the run trains: it has asked to die with its parent
            if log.exists() and "training cpg-actor" in log.read_text():
                break
            time.sleep(0.1)
        (child,) = _children(parent.pid)
        assert _alive(child)
        parent.send_signal(signal.SIGKILL)
        parent.wait()
        for _ in range(600):  # polled until the child is gone
            if not _alive(child):
                break
            time.sleep(0.1)
        assert not _alive(child)
    finally:
        parent.kill()
        if child is not None and _alive(child):
            os.kill(child, signal.SIGKILL)


# -- a GIF of a few MB -------------------------------------------------------------------------
def test_a_gif_keeps_at_most_20_frames_per_second_and_320_pixels_of_width(tmp_path):
    import imageio.v2 as imageio
    import numpy as np

    from cpg_actor.robots.common.video import write_video

    # a quadruped's video: 50 Hz, 640 x 480 (1 s of it), a fine checkerboard of 0 and 200
    checkers = (np.indices((480, 640)).sum(axis=0) % 2 * 200).astype(np.uint8)
    frames = [np.repeat(checkers[:, :, None], 3, axis=2) + i for i in range(50)]
    path = write_video(frames, tmp_path / "trot.gif", fps=50)
    read = imageio.mimread(path)
    assert len(read) == 17 and read[0].shape[:2] == (240, 320)  # every 3rd frame, halved
    for j, frame in enumerate(read):  # each pixel the mean of the block it replaces
        assert (frame[:, :, :3] == 100 + 3 * j).all()
    path = write_video(frames[:5], tmp_path / "full.gif", fps=50, gif_fps=50, gif_width=640)
    assert len(imageio.mimread(path)) == 5 and imageio.mimread(path)[0].shape[:2] == (480, 640)


def test_a_gif_of_an_evaluation_renders_only_the_frames_it_keeps(tmp_path, monkeypatch):
    """Rendering costs more than encoding: `eval --video X.gif` renders every 3rd control step
    of a 50 Hz episode (at most 20 fps), an MP4 every step; both play in real time."""
    import imageio.v2 as imageio
    import numpy as np

    import cpg_actor.training.build as build
    from cpg_actor.commands.eval import record_video
    from cpg_actor.config import TrainConfig
    from cpg_actor.robots.go1.config import Go1Config

    class Env:
        rendered = 0

        def reset(self, seed):
            return np.zeros((1, 1)), {}

        def step(self, action):
            no = np.zeros(1, dtype=bool)
            return np.zeros((1, 1)), None, no, no, {}

        def render_frame(self, index):
            Env.rendered += 1
            return np.full((8, 8, 3), Env.rendered, dtype=np.uint8)

        def close(self):
            pass

    class Policy:
        def reset(self, n):
            pass

        def act(self, obs):
            return type("Step", (), {"action": np.zeros((1, 1))})()

    monkeypatch.setattr(build, "make_env", lambda *args: Env())
    config = TrainConfig(robot="go1", env=Go1Config(episode_seconds=1.2))  # 60 steps at 50 Hz
    record_video(Policy(), config, tmp_path / "walk.gif", seed=0, overwrite=False)
    assert Env.rendered == 21  # the first frame and every 3rd of 60 steps
    durations = [frame.meta["duration"] for frame in imageio.get_reader(tmp_path / "walk.gif")]
    assert len(durations) == 21 and np.allclose(durations, 60.0)  # 3 steps of 20 ms each
    Env.rendered = 0
    record_video(Policy(), config, tmp_path / "walk.mp4", seed=0, overwrite=False)
    assert Env.rendered == 61


# -- a damaged file of a run -------------------------------------------------------------------
@pytest.mark.parametrize(
    ("name", "damage", "message"),
    [
        ("metrics.jsonl", b"garbage{\n", "metrics.jsonl, line {n}: not JSON"),
        ("metrics.jsonl", b"5\n", "metrics.jsonl, line {n}: not a JSON object"),
        ("metrics.jsonl", b"[1, 2]\n", "metrics.jsonl, line {n}: not a JSON object"),
        ("metrics.jsonl", b"\xff\xfe{}\n", "metrics.jsonl is not text"),
        ("config.yaml", None, "config.yaml holds no config keys"),
    ],
)
def test_a_damaged_metrics_file_or_emptied_config_is_one_line(
    tmp_path, capsys, trained, name, damage, message
):
    """eval (its learning-curve figure), export and curves read a run's files: a damaged line
    of metrics.jsonl is named by its number; an emptied config.yaml is not read as defaults."""
    run_dir = copy_of(trained, tmp_path)
    path = run_dir / name
    message = message.format(n=len(path.read_bytes().splitlines()) + 1)  # the damaged line
    path.write_bytes(b"" if damage is None else path.read_bytes() + damage)
    commands = [["eval", str(run_dir), "--episodes", "1"], ["curves", str(run_dir), "--out",
                str(tmp_path / "curves.png"), "--metric", "charts/SPS"]]  # fmt: skip
    if name == "config.yaml":
        commands.append(["export", str(run_dir), "--format", "torchscript"])
    for argv in commands:
        assert main(argv) == 2, argv
        assert message in one_line(capsys), argv
    assert not (tmp_path / "curves.png").exists()


def test_a_metrics_line_cut_short_by_an_interrupted_run_is_left_out(tmp_path, capsys, trained):
    run_dir = copy_of(trained, tmp_path)
    with open(run_dir / "metrics.jsonl", "ab") as handle:
        handle.write(b'{"iteration": 2, "global_st')  # no end: a write cut off
    figure = tmp_path / "curves.png"
    assert main(["curves", str(run_dir), "--out", str(figure), "--metric", "charts/SPS"]) == 0
    assert figure.is_file()


def test_resuming_over_a_metrics_line_that_is_not_an_object_is_one_line(tmp_path, capsys, trained):
    run_dir = copy_of(trained, tmp_path)
    metrics = run_dir / "metrics.jsonl"
    metrics.write_bytes(metrics.read_bytes() + b"5\n")
    before = metrics.read_bytes()
    argv = ["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "32", "--no-progress"]
    assert main(argv) == 2
    assert "not a row of metrics (a JSON object)" in one_line(capsys)
    assert metrics.read_bytes() == before  # nothing appended to the damaged log
