"""Headless rendering on both simulators and the video helper."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import imageio.v2 as imageio
import numpy as np
import pytest

from cpg_actor.robots.common.mujoco_runtime import mujoco, offscreen_renderer
from cpg_actor.robots.common.video import RenderingUnavailable, write_video
from cpg_actor.robots.hopper.env import HopperEnv


def rendered(sim: str) -> np.ndarray:
    env = HopperEnv(sim=sim, render_mode="rgb_array", render_width=160, render_height=120)
    env.reset(seed=0)
    env.step(np.array([0.5, -1.0]))
    try:
        return env.render()
    finally:
        env.close()


def mujoco_gl_error() -> str | None:
    """Why no MuJoCo GL context can be made here, or None if one can (asked as the envs ask,
    so that a GL layer that cannot work is never tried twice: GLFW without a display aborts
    the interpreter the second time)."""
    try:
        renderer = offscreen_renderer(mujoco.MjModel.from_xml_string("<mujoco/>"), 8, 8)
    except RenderingUnavailable as error:
        return str(error)
    renderer.close()
    return None


def test_mujoco_renders_headless():
    error = mujoco_gl_error()
    if error is not None:
        pytest.skip(f"no MuJoCo GL context (MUJOCO_GL={os.environ.get('MUJOCO_GL')}): {error}")
    frame = rendered("mujoco")
    assert frame.shape == (120, 160, 3) and frame.dtype == np.uint8
    assert frame.std() > 10  # a picture, not a blank


def test_pybullet_renders_with_tiny_renderer():
    frame = rendered("pybullet")
    assert frame.shape == (120, 160, 3) and frame.dtype == np.uint8
    assert frame.std() > 10


def frames(count=6, height=33, width=45):
    ramp = np.linspace(0, 255, count).astype(np.uint8)
    return [np.full((height, width, 3), value, dtype=np.uint8) for value in ramp]


@pytest.mark.parametrize("suffix", [".mp4", ".gif"])
def test_write_video(tmp_path, suffix):
    path = tmp_path / f"hop{suffix}"
    assert write_video(frames(), path, fps=20) == path
    read = imageio.mimread(path)
    assert len(read) == 6
    assert read[0].shape[:2] == ((34, 46) if suffix == ".mp4" else (33, 45))  # H.264: even
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]  # no temporary left
    with pytest.raises(FileExistsError):
        write_video(frames(), path, fps=20)
    write_video(frames(count=3), path, fps=20, overwrite=True)
    assert len(imageio.mimread(path)) == 3


def test_write_video_rejects_bad_input(tmp_path):
    with pytest.raises(ValueError, match=".mp4 or .gif"):
        write_video(frames(), tmp_path / "hop.avi", fps=20)
    with pytest.raises(ValueError, match="no frames"):
        write_video([], tmp_path / "hop.gif", fps=20)
    with pytest.raises(ValueError, match="uint8"):
        write_video([np.zeros((4, 4, 3))], tmp_path / "hop.gif", fps=20)
    with pytest.raises(ValueError, match="fps"):
        write_video(frames(), tmp_path / "hop.gif", fps=0)
    with pytest.raises(ValueError, match="same shape"):
        write_video(frames(height=4) + frames(height=6), tmp_path / "hop.gif", fps=20)
    assert list(tmp_path.iterdir()) == []


def test_demo_command_prints_the_return_and_writes_a_strip(tmp_path, capsys):
    from cpg_actor.robots.hopper.demo import main

    image = tmp_path / "strip.png"
    args = ["--sim", "pybullet", "--seconds", "0.5", "--width", "48", "--height", "40"]
    assert main([*args, "--image", str(image)]) == 0
    assert "return" in capsys.readouterr().out
    assert imageio.imread(image).shape[:2] == (40, 4 * 48)
    assert main([*args, "--image", str(image)]) == 2  # exists: refused without --overwrite


@pytest.mark.parametrize("sim", ["mujoco", "pybullet"])
def test_check_env_with_rendering(sim):
    import warnings

    from gymnasium.utils.env_checker import check_env

    if sim == "mujoco" and mujoco_gl_error() is not None:
        pytest.skip(f"no MuJoCo GL context: {mujoco_gl_error()}")
    env = HopperEnv(sim=sim, render_mode="rgb_array", render_width=64, render_height=48)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the action-space remark, see test_hopper_env.py
        check_env(env)
    env.close()


def test_headless_gl_backend_falls_back_to_none_without_opengl_libraries():
    """With no display, MUJOCO_GL is chosen from the OpenGL libraries installed: importing
    mujoco must not fail on a machine with neither EGL nor OSMesa (training needs neither)."""
    from cpg_actor.robots.common.mujoco_runtime import headless_gl

    assert headless_gl(lambda name: f"lib{name}.so") == "egl"
    assert headless_gl(lambda name: "libOSMesa.so" if name == "OSMesa" else None) == "osmesa"
    assert headless_gl(lambda name: None) == "disable"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="GLFW without a display")
def test_mujoco_imported_first_without_a_display_is_refused_not_an_abort():
    """A process that imported mujoco before cpg_actor, with no MUJOCO_GL and no display, has
    mujoco bound to GLFW: rendering is refused with a clear error every time, instead of
    GLFW failing (its second failure aborted the interpreter)."""
    code = textwrap.dedent("""
        import mujoco
        from cpg_actor.robots.common.mujoco_runtime import gl_backend, offscreen_renderer
        from cpg_actor.robots.common.video import RenderingUnavailable
        print(gl_backend())
        model = mujoco.MjModel.from_xml_string("<mujoco/>")
        for _ in range(2):
            try:
                offscreen_renderer(model, 8, 8)
            except RenderingUnavailable as error:
                print(error)
    """)
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "MUJOCO_GL")}
    result = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0] == "glfw"
    assert len(lines) == 3 and all("imported before MUJOCO_GL was chosen" in x for x in lines[1:])


@pytest.mark.slow
def test_eval_video_only_adds_a_video_to_an_evaluated_run(tmp_path, capsys):
    """`cpg-actor eval --video PATH --video-only` records the video without touching (or
    needing --overwrite for) the traces of an earlier evaluation."""
    reason = mujoco_gl_error()
    if reason is not None:
        pytest.skip(f"no MuJoCo GL context here: {reason}")
    from cpg_actor.cli import main

    run_dir = tmp_path / "run"
    tiny = ["--num-envs", "2", "--set", "ppo.num_steps=8", "--set", "ppo.num_minibatches=2"]
    tiny += ["--set", "ppo.num_epochs=1", "--set", "env.episode_steps=20", "--no-progress"]
    assert main(["train", "--run-dir", str(run_dir), "--total-steps", "16", *tiny]) == 0
    assert main(["eval", str(run_dir), "--episodes", "1"]) == 0
    traces = run_dir / "eval" / "traces.npz"
    before = traces.read_bytes()
    video = tmp_path / "hop.mp4"
    assert main(["eval", str(run_dir), "--video", str(video), "--video-only"]) == 0
    assert video.stat().st_size > 0 and traces.read_bytes() == before
    assert main(["eval", str(run_dir), "--video", str(video), "--video-only"]) == 2  # exists
    assert main(["eval", str(run_dir), "--video-only"]) == 2
    assert "--video-only needs --video" in capsys.readouterr().err
