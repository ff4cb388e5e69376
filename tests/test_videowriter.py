"""Every MP4 particlebot writes is H.264: the one writer, and the commands that film (render,
track --overlay), checked with ffmpeg's own probe."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import cv2
import imageio_ffmpeg
import numpy as np
import pytest

from particlebot.cli import main
from particlebot.videowriter import VideoError, VideoWriter


def probe(path: Path) -> tuple[str, tuple[int, int]]:
    """(codec, (width, height)) of the first video stream, as ffmpeg -i reports it."""
    result = subprocess.run(
        [imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-i", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    found = re.search(r"Video: (\w+).*?, (\d+)x(\d+)", result.stderr)
    assert found is not None, result.stderr
    return found.group(1), (int(found.group(2)), int(found.group(3)))


def moving_square(index: int, size: tuple[int, int]) -> np.ndarray:
    width, height = size
    frame = np.zeros((height, width, 3), np.uint8)
    frame[10:30, 4 * index : 4 * index + 20] = (0, 0, 255)  # red in BGR
    return frame


@pytest.mark.parametrize(("suffix", "codec"), [(".mp4", "h264"), (".avi", "mjpeg")])
def test_the_writer_writes_h264_mp4_and_mjpeg_avi(tmp_path: Path, suffix: str, codec: str) -> None:
    path = tmp_path / f"clip{suffix}"
    size = (65, 49)  # odd: H.264 needs even sizes, so the writer pads
    with VideoWriter(path, 10, size) as writer:
        for index in range(12):
            writer.write(moving_square(index, size))
    assert probe(path) == (codec, (66, 50))
    capture = cv2.VideoCapture(str(path))
    frames = []
    while True:
        ok, frame = capture.read()
        if not ok:
            break
        frames.append(frame)
    capture.release()
    assert len(frames) == 12
    # The square is where it was drawn, red (BGR order kept), in the first and the last frame.
    for index in (0, 11):
        square = frames[index][12:28, 4 * index + 2 : 4 * index + 18].reshape(-1, 3).mean(axis=0)
        assert square[2] > 180 and square[0] < 60 and square[1] < 60
        assert frames[index][40:48, :].mean() < 20


def test_a_container_it_cannot_write_is_refused_in_one_line(tmp_path: Path) -> None:
    with pytest.raises(VideoError, match=re.escape("write videos as .mp4 or .avi, not clip.webm")):
        VideoWriter(tmp_path / "clip.webm", 10, (64, 48))


def test_render_and_track_overlay_write_h264(tmp_path: Path) -> None:
    video = tmp_path / "blob.mp4"
    assert (
        main(["render", "-o", str(video), "--size", "320x180", "--duration-s", "2", "--fps", "2"])
        == 0
    )
    assert probe(video)[0] == "h264"
    overlay = tmp_path / "seen.mp4"
    assert main(["track", str(video), "--rate", "0", "--overlay", str(overlay)]) == 0
    assert probe(overlay) == ("h264", (320, 180))
