"""The run's film: encoded by ffmpeg with its progress passed on frame by frame, written whole."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from particlebot.sim.runs.video import encode, frame_path


def test_encoding_reports_its_frames_and_leaves_only_the_film(tmp_path: Path) -> None:
    frames = tmp_path / "frames"
    frames.mkdir()
    count = 12
    for index in range(count):
        picture = np.zeros((64, 64, 3))
        picture[:, : 4 * index + 4] = 1.0  # a bar that grows, so frames differ
        plt.imsave(frame_path(frames, index), picture)
    reports: list[tuple[int, int]] = []
    film = encode(frames, tmp_path / "run.mp4", progress=lambda *r: reports.append(r))
    assert film == tmp_path / "run.mp4" and film.stat().st_size > 0
    assert reports[0] == (0, count) and reports[-1] == (count, count)
    assert [done for done, _ in reports] == sorted(done for done, _ in reports)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frames", "run.mp4"]
