"""Reading videos (mp4, avi) through OpenCV, with errors a person can act on; writing them is
particlebot.videowriter's (H.264 through ffmpeg), re-exported here."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import numpy.typing as npt

from particlebot.closing import ClosedOnExit
from particlebot.videowriter import VideoError, VideoWriter

__all__ = ["Image", "VideoError", "VideoSource", "VideoWriter", "as_image", "open_video"]

Image = npt.NDArray[np.uint8]


def as_image(array: object) -> Image:
    """An OpenCV result as the uint8 image it is (no copy); OpenCV's stubs type it loosely."""
    return np.asarray(array, dtype=np.uint8)


@dataclass
class VideoSource(ClosedOnExit):
    """An opened video: its size, frame rate and (estimated) length."""

    path: Path
    capture: cv2.VideoCapture
    fps: float
    size: tuple[int, int]
    frame_count: int
    """From the container; 0 when it does not say. Some containers round it."""
    first: Image
    """The first frame, read to prove the file decodes."""

    def frames(self, step: int = 1) -> Iterator[tuple[int, Image]]:
        """(index, frame) of every step-th frame from the first; skipped ones are only grabbed."""
        yield 0, self.first
        index = 0
        while True:
            for _ in range(step - 1):
                if not self.capture.grab():
                    return
                index += 1
            ok, frame = self.capture.read()
            if not ok:
                return
            index += 1
            yield index, as_image(frame)

    def close(self) -> None:
        self.capture.release()


def open_video(path: Path, fps: float | None = None) -> VideoSource:
    """Opens path and decodes its first frame; VideoError if missing, unreadable or empty.
    fps overrides a frame rate the container lacks or gets wrong."""
    if not path.exists():
        raise VideoError(f"no such video: {path}")
    if path.is_dir():
        raise VideoError(f"{path} is a folder, not a video")
    if path.stat().st_size == 0:
        raise VideoError(f"{path} is empty (0 bytes)")
    capture = cv2.VideoCapture(str(path))
    if not capture.isOpened():
        capture.release()
        raise VideoError(f"cannot decode {path}: not a video OpenCV's FFmpeg can read")
    ok, first = capture.read()
    if not ok or first is None:
        capture.release()
        raise VideoError(f"{path} has no frames")
    container_fps = capture.get(cv2.CAP_PROP_FPS)
    rate = fps if fps is not None else container_fps
    if not rate or not np.isfinite(rate) or rate <= 0 or rate > 1000:
        capture.release()
        raise VideoError(f"{path} does not say its frame rate; give it with --fps")
    count = int(capture.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
    height, width = first.shape[:2]
    return VideoSource(path, capture, float(rate), (width, height), max(count, 0), as_image(first))
