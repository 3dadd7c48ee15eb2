"""Write rendered frames to a video file: MP4 (H.264 via imageio-ffmpeg) or GIF, by extension."""

from __future__ import annotations

import itertools
import math
import os
import uuid
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from cpg_actor.errors import RenderingUnavailable  # noqa: F401 (the CLI catches it from there)

VIDEO_SUFFIXES = (".mp4", ".gif")
# a GIF's frames per second and width at most: GIF stores every pixel of every frame nearly
# raw, so a full-rate, full-size episode is tens of MB. Browsers slow down frames shorter
# than 20 ms (above 50 fps)
GIF_FPS = 20.0
GIF_WIDTH = 320


def frame_stride(path: str | os.PathLike, fps: float, gif_fps: float = GIF_FPS) -> int:
    """Every how many frames a video at ``fps`` keeps one: a GIF at most ``gif_fps`` per
    second, an MP4 every frame. A caller that renders frames can render only those (rendering
    costs more than encoding) and pass ``fps / stride``."""
    return math.ceil(fps / gif_fps) if Path(path).suffix.lower() == ".gif" else 1


def write_video(
    frames: Iterable[np.ndarray],
    path: str | os.PathLike,
    fps: float,
    overwrite: bool = False,
    gif_fps: float = GIF_FPS,
    gif_width: int = GIF_WIDTH,
) -> Path:
    """Write RGB frames (H, W, 3) uint8 to ``path`` (``.mp4`` or ``.gif``) and return the path.
    A GIF keeps every k-th frame (at most ``gif_fps`` per second, at most 50), each shown k
    times as long so that it plays in real time, shrunk by a whole factor to at most
    ``gif_width`` pixels wide (each pixel the mean of the block it replaces).

    The file appears atomically (written next to it under a temporary name, then renamed).
    An existing file is an error unless ``overwrite=True``. MP4 frames are padded to even
    width and height (H.264 needs it) and encoded as they come: ``frames`` may be a generator
    (an episode rendered while it runs is never held in memory whole).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in VIDEO_SUFFIXES:
        raise ValueError(f"video path must end in {' or '.join(VIDEO_SUFFIXES)}, got {path}")
    if not (isinstance(fps, (int, float)) and not isinstance(fps, bool) and 0 < fps < 1000):
        raise ValueError(f"fps must be a number in (0, 1000), got {fps!r}")
    if not (isinstance(gif_fps, (int, float)) and 0 < gif_fps <= 50):
        raise ValueError(f"gif_fps must be a number in (0, 50], got {gif_fps!r}")
    if isinstance(gif_width, bool) or not (isinstance(gif_width, int) and gif_width >= 1):
        raise ValueError(f"gif_width must be an integer >= 1, got {gif_width!r}")
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True to replace it")
    checked = (_check_frame(frame, i) for i, frame in enumerate(frames))
    first = next(checked, None)
    if first is None:
        raise ValueError("no frames to write")

    def same_shape(frame: np.ndarray) -> np.ndarray:
        if frame.shape != first.shape:
            raise ValueError("all frames must have the same shape")
        return frame

    k = frame_stride(path, fps, gif_fps)  # a GIF's frames kept: every k-th
    if suffix == ".gif":  # not streamed: checked whole before anything is written
        scale = math.ceil(first.shape[1] / gif_width)
        gif_frames = [
            _shrink(frame, scale)
            for i, frame in enumerate(itertools.chain([first], map(same_shape, checked)))
            if i % k == 0
        ]
    path.parent.mkdir(parents=True, exist_ok=True)
    import imageio.v2 as imageio

    # a hidden name next to the target (same file system: the rename is atomic)
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp{suffix}")
    try:
        if suffix == ".mp4":
            height, width = first.shape[:2]
            pad = ((0, height % 2), (0, width % 2), (0, 0))
            with imageio.get_writer(
                tmp, format="FFMPEG", mode="I", fps=fps, codec="libx264", quality=7,
                macro_block_size=1, output_params=["-pix_fmt", "yuv420p"],
            ) as writer:  # fmt: skip
                for frame in itertools.chain([first], map(same_shape, checked)):
                    writer.append_data(
                        np.pad(frame, pad, mode="edge") if any(pad[0] + pad[1]) else frame
                    )
        else:
            # ms per frame, rounded off float error: GIF keeps whole 10 ms and Pillow truncates
            duration = round(1000.0 * k / fps, 6)
            imageio.mimsave(tmp, gif_frames, format="GIF", duration=duration, loop=0)
        tmp.replace(path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def _check_frame(frame: np.ndarray, index: int) -> np.ndarray:
    array = np.asarray(frame)
    if array.ndim != 3 or array.shape[2] not in (3, 4):
        raise ValueError(f"frame {index} must be (H, W, 3) RGB, got shape {array.shape}")
    if array.dtype != np.uint8:
        raise ValueError(f"frame {index} must be uint8, got {array.dtype}")
    return np.ascontiguousarray(array[:, :, :3])


def _shrink(frame: np.ndarray, scale: int) -> np.ndarray:
    """``frame`` ``scale`` times smaller each way, each pixel the mean of its block (the edge
    rows and columns that fill no block dropped)."""
    if scale == 1:
        return frame
    height, width = frame.shape[0] // scale, frame.shape[1] // scale
    blocks = frame[: height * scale, : width * scale].reshape(height, scale, width, scale, 3)
    return blocks.mean(axis=(1, 3)).round().astype(np.uint8)
