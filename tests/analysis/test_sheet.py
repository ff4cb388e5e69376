"""The contact sheet's choice of frames: spread evenly, the run's last frame always shown."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from particlebot.analysis.sheet import ContactSheet


def run(sheet: ContactSheet, frames: int) -> list[int]:
    drawn = []
    for ordinal in range(frames):
        if sheet.wants(ordinal):
            drawn.append(ordinal)
            sheet.offer(ordinal, np.full((18, 32, 3), ordinal % 256, np.uint8))
    sheet.end(frames - 1, lambda: np.full((18, 32, 3), 255, np.uint8))
    return [ordinal for ordinal, _ in sheet._picks()]


@pytest.mark.parametrize(
    ("expected", "frames"), [(1000, 1000), (0, 1000), (1000, 900), (900, 1000)]
)
def test_twelve_panels_from_first_to_last_frame(expected: int, frames: int) -> None:
    picks = run(ContactSheet(expected, thumb_width=32), frames)
    # A container that overstates the length leaves its last planned panels unreached.
    assert len(picks) == (11 if expected > frames else 12)
    assert picks[0] == 0 and picks[-1] == frames - 1
    gaps = np.diff(picks)
    assert gaps.min() > 0.4 * frames / 11  # no bunching, whatever the container said


def test_a_short_run_shows_every_frame(tmp_path: Path) -> None:
    sheet = ContactSheet(5, thumb_width=32)
    assert run(sheet, 5) == [0, 1, 2, 3, 4]
    sheet.write(tmp_path / "s.png", "five")
    image = cv2.imread(str(tmp_path / "s.png"))
    assert image is not None and image.shape[1] == 3 * (32 + 4)
