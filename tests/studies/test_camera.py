"""Table S3 through the paper's camera: the published camera rule, and one tiny run filmed as the
published simulator drew it, tracked and read with one pixel scale."""

from __future__ import annotations

from pathlib import Path

import pytest

from particlebot.studies.camera import film_dead_runs
from particlebot.studies.published import camera_height_m, camera_px_per_m, paper_camera_factor


def test_the_published_camera_hangs_higher_for_larger_swarms() -> None:
    heights = [camera_height_m(n) for n in (10, 100, 1000, 10000)]
    assert heights == pytest.approx([9.456, 13.744, 21.056, 32.898])
    assert camera_height_m(11) == camera_height_m(10) and camera_height_m(12) == heights[1]
    # A 60-degree vertical field of view over 1080 rows: 935 px / height.
    assert camera_px_per_m(1.0) == pytest.approx(935.3, abs=0.1)
    assert [paper_camera_factor(n) for n in (10, 100, 1000, 10000)] == pytest.approx(
        [2.2267, 1.5320, 1.0, 0.6400], abs=1e-4
    )
    with pytest.raises(ValueError, match="no camera for 10002"):
        camera_height_m(10002)


def test_a_filmed_run_reads_its_true_speed_times_the_one_scale_factor(tmp_path: Path) -> None:
    lines: list[str] = []
    (row,) = film_dead_runs([(10, 0.0)], range(1, 2), 600.0, 120.0, tmp_path, say=lines.append)
    true, tracked, camera = (
        float(row[k]) for k in ("true_mm_s", "tracked_mm_s", "paper_camera_mm_s")
    )
    # A frame or two may be dropped as a spike: whether one is depends on the last bits of the
    # world's path, which another CPU target (no FMA, say) changes.
    assert int(row["frames"]) == 21 and int(row["dropped"]) <= 2
    # The tracked region's centroid follows the particles' mean: the same speed to a few % over
    # 8 minutes (the region leans toward expanded particles by up to a few cm).
    assert tracked == pytest.approx(true, rel=0.1)
    # One scale for every size: the 10-particle camera's pixels read 2.23 times too long.
    # (The row holds each speed to 6 significant digits, so the product agrees to ~1e-5.)
    assert camera == pytest.approx(tracked * paper_camera_factor(10), rel=1e-5)
    assert "paper camera" in lines[0]
    # Rows already measured are not run again.
    again = film_dead_runs([(10, 0.0)], range(1, 2), 600.0, 120.0, tmp_path, say=lines.append)
    assert again == [row] and len(lines) == 1
