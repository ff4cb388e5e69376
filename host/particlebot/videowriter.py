"""The one way particlebot writes video: frames piped to the ffmpeg that the imageio-ffmpeg wheel
carries, every MP4 as H.264 (yuv420p), which browsers, slide software and phones play; an AVI as
Motion JPEG. OpenCV only decodes (particlebot.analysis.video)."""

from __future__ import annotations

from collections.abc import Generator
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from particlebot.closing import ClosedOnExit
from particlebot.errors import ParticlebotError

H264_OUTPUT = ["-vf", "format=yuv420p", "-c:v", "libx264", "-crf", "23"]
"""ffmpeg's output options for an MP4 made from images (particlebot.sim.runs.video)."""
MP4_SUFFIXES = (".mp4", ".m4v", ".mov")
# codec, pixel format, options: each container gets what every player reads.
_CODECS: dict[str, tuple[str, str, list[str]]] = {
    **{suffix: ("libx264", "yuv420p", ["-crf", "23"]) for suffix in MP4_SUFFIXES},
    ".avi": ("mjpeg", "yuvj420p", ["-q:v", "3"]),
}


class VideoError(ParticlebotError, ValueError):
    """A video that cannot be read or written, said in one line."""


class VideoWriter(ClosedOnExit):
    """Writes frames of one size (uint8, height x width x 3, BGR as OpenCV draws them, or RGB)
    to .mp4/.m4v/.mov (H.264) or .avi (Motion JPEG); a frame of another size is scaled."""

    def __init__(
        self, path: Path, fps: float, size: tuple[int, int], *, channels: str = "bgr"
    ) -> None:
        codec = _CODECS.get(path.suffix.lower())
        if codec is None:
            raise VideoError(f"write videos as .mp4 or .avi, not {path.name}")
        if not path.parent.is_dir():
            raise VideoError(f"no such folder for {path}")
        if channels not in ("bgr", "rgb"):
            raise ValueError(f"channels are bgr or rgb, not {channels!r}")
        import imageio_ffmpeg

        self.path = path
        self.size = size
        self.frames = 0
        name, pixels, options = codec
        # H.264's colour subsampling needs even sizes: ffmpeg pads to them rather than rescaling.
        self._writer: Generator[Any, Any, None] = imageio_ffmpeg.write_frames(
            str(path),
            size,
            pix_fmt_in=f"{channels}24",
            pix_fmt_out=pixels,
            fps=fps,
            codec=name,
            quality=None,
            macro_block_size=1,
            ffmpeg_log_level="error",
            output_params=[*options, "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"],
        )
        try:
            self._writer.send(None)  # starts ffmpeg
        except (OSError, RuntimeError) as exc:
            raise VideoError(f"cannot write {path}: {exc}") from None

    def write(self, frame: npt.NDArray[np.uint8]) -> None:
        if (frame.shape[1], frame.shape[0]) != self.size:
            import cv2

            frame = np.asarray(cv2.resize(frame, self.size, interpolation=cv2.INTER_AREA))
        try:
            self._writer.send(np.ascontiguousarray(frame, dtype=np.uint8))
        except (OSError, RuntimeError) as exc:
            raise VideoError(f"cannot write {self.path}: {exc}") from None
        self.frames += 1

    def close(self) -> None:
        try:
            self._writer.close()
        except (OSError, RuntimeError) as exc:
            raise VideoError(f"ffmpeg could not finish {self.path}: {exc}") from None
