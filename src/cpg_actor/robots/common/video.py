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


def write_video(
    frames: Iterable[np.ndarray], path: str | os.PathLike, fps: float, overwrite: bool = False
) -> Path:
    """Write RGB frames (H, W, 3) uint8 to ``path`` (``.mp4`` or ``.gif``) and return the path.
    A GIF keeps at most 50 frames per second (browsers slow down faster ones).

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

    if suffix == ".gif":  # not streamed: checked whole before anything is written
        gif_frames = [first, *(same_shape(frame) for frame in checked)]
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
            # browsers draw a frame shorter than 20 ms for 100 ms: above 50 fps keep every
            # k-th frame, each shown k times as long, so the GIF plays in real time
            k = math.ceil(fps / 50)
            imageio.mimsave(tmp, gif_frames[::k], format="GIF", duration=1000.0 * k / fps, loop=0)
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
