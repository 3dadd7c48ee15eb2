"""`cpg-actor eval` on a quadruped run: the ANYmal B's video (rendered by the env, a camera
following the base), the gait diagram and the commanded vs measured forward speed, kept unless
--overwrite; the step info the figures are drawn from."""

from __future__ import annotations

import imageio.v2 as imageio
import numpy as np
import pytest

from cpg_actor.cli import main
from cpg_actor.robots.anymal.vector import AnymalVectorEnv
from cpg_actor.robots.common import mujoco_runtime
from cpg_actor.robots.common.mujoco_runtime import mujoco  # MUJOCO_GL chosen on import
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.common.video import RenderingUnavailable, write_video

FRAME = (QuadrupedConfig().render_height, QuadrupedConfig().render_width, 3)

TINY = ["--num-envs", "2", "--set", "ppo.num_steps=8", "--set", "ppo.num_minibatches=2",
        "--set", "ppo.num_epochs=1", "--set", "eval_interval=0",
        "--set", "env.episode_seconds=0.1", "--no-progress"]  # fmt: skip
FIGURES = ("gait_diagram.png", "forward_speed.png")


def skip_without_gl() -> None:
    from robots.hopper.test_render_video import mujoco_gl_error

    reason = mujoco_gl_error()
    if reason is not None:
        pytest.skip(f"no MuJoCo GL context here: {reason}")


@pytest.fixture(scope="module")
def anymal_run(tmp_path_factory):
    """A tiny trained anymal run (32 steps; episodes of 5 control steps)."""
    run = tmp_path_factory.mktemp("anymal") / "run"
    args = ["train", "--robot", "anymal", "--total-steps", "32", "--run-dir", str(run), *TINY]
    assert main(args) == 0
    return run


def orange(frame: np.ndarray) -> int:
    """Pixels of the robot's legs."""
    red, green, blue = (frame[..., c].astype(int) for c in range(3))
    return int(((red > 150) & (green < 120) & (blue < 80)).sum())


def test_render_frame_follows_the_base_and_streams_into_a_video(tmp_path):
    skip_without_gl()
    env = AnymalVectorEnv(2, {"episode_seconds": 0.1})
    try:
        with pytest.raises(RuntimeError, match="reset"):
            env.render_frame(0)
        env.reset(seed=0)
        with pytest.raises(ValueError, match="index"):
            env.render_frame(2)
        here = env.render_frame(1)
        assert here.shape == FRAME and here.dtype == np.uint8
        assert here.std() > 10  # a picture, not a blank
        env.qpos[1, 0] += 20.0  # 20 m on: the camera and the light follow it, the ground moves
        there = env.render_frame(1)
    finally:
        env.close()
    assert orange(there) == pytest.approx(orange(here), rel=0.1) and orange(here) > 1000
    assert there.mean() == pytest.approx(here.mean(), rel=0.1)  # not in the dark
    assert not np.array_equal(there, here)

    env = AnymalVectorEnv(1, {"episode_seconds": 0.1})

    def frames():
        env.reset(seed=0)
        yield env.render_frame(0)
        for _ in range(6):
            env.step(env.qpos[:, 7:].copy())
            yield env.render_frame(0)

    path = tmp_path / "anymal.mp4"
    try:
        write_video(frames(), path, fps=50)
    finally:
        env.close()
    assert path.stat().st_size > 0
    assert len(imageio.mimread(path)) == 7
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no temporary left


def test_no_opengl_is_one_clear_error(monkeypatch):
    def no_gl(*args, **kwargs):
        raise mujoco.FatalError("an OpenGL platform library has not been loaded")

    monkeypatch.setattr(mujoco_runtime.mujoco, "Renderer", no_gl)
    env = AnymalVectorEnv(1)
    try:
        env.reset(seed=0)
        with pytest.raises(RenderingUnavailable, match="MUJOCO_GL=.*egl.*osmesa"):
            env.render_frame(0)
    finally:
        env.close()


def test_step_info_command_is_the_episodes_own_on_its_last_step():
    """The command of the step that ends an episode is that episode's (the next one's is in
    the reset observation), so a trace of it never shows the next episode's."""
    env = AnymalVectorEnv(3, {"episode_seconds": 0.1, "command_range": (0.0, 1.0)})
    try:
        _, info = env.reset(seed=3)
        started = info["command"].copy()
        for _ in range(5):
            _, _, terminated, truncated, info = env.step(env.qpos[:, 7:].copy())
            assert np.array_equal(info["command"], started)
        assert (terminated | truncated).all()
        assert not np.array_equal(env.command, started)  # the next episodes' commands
        assert info["contact"].shape == (3, 4) and info["contact"].dtype == bool
        assert env.foot_names == ("LF", "RF", "LH", "RH")
    finally:
        env.close()


def test_eval_writes_the_gait_diagram_and_speed_figures_and_keeps_them(anymal_run, capsys):
    eval_dir = anymal_run / "eval"
    assert main(["eval", str(anymal_run), "--episodes", "2"]) == 0
    out = capsys.readouterr().out
    for name in FIGURES:
        assert (eval_dir / name).stat().st_size > 5_000, name
        assert f"figure {eval_dir / name}" in out
    traces = np.load(eval_dir / "traces.npz")
    steps = int(traces["length"][0])
    assert traces["foot_contact"].shape == (steps, 2, 4)
    assert traces["base_forward_speed"].shape == (steps, 2)
    assert traces["command"].shape == (steps, 2, 3)
    assert list(traces["foot_names"]) == ["LF", "RF", "LH", "RH"]
    assert set(np.unique(traces["foot_contact"][:steps, 0])) <= {0.0, 1.0}
    assert np.all(traces["command"][:, 0] == traces["command"][0, 0])  # episode 0: one command
    # the physical metrics that apply to a quadruped (no hip on a rail: no hop apex)
    assert traces["joint_torque"].shape == (steps, 2, 12)
    assert traces["foot_position"].shape == (steps, 2, 4, 3)
    assert [str(n) for n in traces["physical_names"]] == [
        "joint_smoothness", "command_smoothness", "torque_rate", "mechanical_power", "foot_slip",
        "time_at_joint_stop"]  # fmt: skip
    assert np.isfinite(traces["physical_torque_rate"]).all()
    assert "physical (mean over episodes): joint smoothness" in out
    assert [p.name for p in eval_dir.iterdir() if p.name.startswith(".")] == []  # no temporary

    # another traces file in the same folder would redraw the figures: refused
    before = {name: (eval_dir / name).read_bytes() for name in FIGURES}
    other = eval_dir / "other.npz"
    assert main(["eval", str(anymal_run), "--episodes", "1", "--output", str(other)]) == 2
    assert "training_curves.png exists; pass --overwrite" in capsys.readouterr().err
    assert not other.exists()
    assert {name: (eval_dir / name).read_bytes() for name in FIGURES} == before
    args = ["eval", str(anymal_run), "--episodes", "1", "--output", str(other), "--overwrite"]
    assert main(args) == 0
    assert other.is_file()
    assert (eval_dir / "forward_speed.png").read_bytes() != before["forward_speed.png"]


def test_eval_video_of_the_quadruped_has_one_frame_per_step(anymal_run, tmp_path):
    skip_without_gl()
    video = tmp_path / "anymal.mp4"
    output = tmp_path / "traces.npz"
    args = ["eval", str(anymal_run), "--episodes", "1", "--output", str(output)]
    assert main([*args, "--video", str(video)]) == 0
    length = int(np.load(output)["length"][0])  # the same episode (seed, mean action)
    assert video.stat().st_size > 0
    frames = imageio.mimread(video)
    assert len(frames) == length
    assert frames[0].shape == FRAME
    assert main(["eval", str(anymal_run), "--video", str(video), "--video-only"]) == 2  # exists


def test_eval_set_overrides_the_env_for_the_evaluation_only(anymal_run, tmp_path, capsys):
    """`--set env.command_range=[0.5,0.5]`: every evaluation episode runs at 0.5 m/s (the issue's
    target is measured so); the run's config is untouched; other keys are refused."""
    config_before = (anymal_run / "config.yaml").read_text()
    output = tmp_path / "fixed.npz"
    args = ["eval", str(anymal_run), "--episodes", "2", "--output", str(output)]
    assert main([*args, "--set", "env.command_range=[0.5, 0.5]"]) == 0
    commands = np.load(output)["command"][:, :, 0]
    assert np.all(commands[np.isfinite(commands)] == 0.5)
    assert (anymal_run / "config.yaml").read_text() == config_before
    bad = ["eval", str(anymal_run), "--output", str(tmp_path / "bad" / "x.npz")]
    assert main([*bad, "--set", "ppo.learning_rate=1"]) == 2
    assert "eval overrides env fields only" in capsys.readouterr().err
    assert main([*bad, "--set", "env.command_range=[1, 0]"]) == 2
    assert "command_range" in capsys.readouterr().err
