"""The ground truth itself: region centroids of known shapes, the blob's phase-delayed breathing,
and simulator runs placed on the filmed field."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from particlebot.analysis.synthetic import (
    R_MAX_CM,
    R_MIN_CM,
    BlobSpec,
    Placement,
    SwarmFrame,
    breathing_blob,
    frames_from_run,
)
from particlebot.sim.runs.simcsv import read_published_csv, write_published_csv


def test_the_region_of_discs_is_their_union_with_enclosed_gaps_filled() -> None:
    one = SwarmFrame(0.0, np.array([10.0]), np.array([20.0]), np.array([7.75]))
    area, x, y = one.region()
    assert area == pytest.approx(math.pi * 7.75**2, rel=0.002)
    assert (x, y) == pytest.approx((10.0, 20.0), abs=0.01)
    # Two touching discs, one expanded: the region leans toward the bigger one.
    pair = SwarmFrame(0.0, np.array([0.0, 19.5]), np.array([0.0, 0.0]), np.array([7.75, 11.75]))
    area, x, _ = pair.region()
    expected = (0 * 7.75**2 + 19.5 * 11.75**2) / (7.75**2 + 11.75**2)
    assert x == pytest.approx(expected, abs=0.05)
    assert pair.centre_mean() == (9.75, 0.0)
    # Three touching discs enclose a small gap, which the region includes.
    r = 7.75
    trio = SwarmFrame(
        0.0, np.array([0, 2 * r, r]), np.array([0, 0, r * math.sqrt(3)]), np.full(3, r)
    )
    gap = (math.sqrt(3) / 4 * (2 * r) ** 2) - math.pi * r**2 / 2
    assert trio.region()[0] == pytest.approx(3 * math.pi * r**2 + gap, rel=0.003)


def test_the_blob_breathes_by_eq_4_one_half_period_later_per_rank() -> None:
    spec = BlobSpec(count=7, duration_s=30.0, fps=20.0, speed_mm_s=0.0, cycle_s=3.0)
    frames = breathing_blob(spec)
    radii = np.array([f.r_cm for f in frames])
    t = np.array([f.t_s for f in frames])
    assert radii.min() == pytest.approx(R_MIN_CM) and radii.max() == pytest.approx(
        R_MAX_CM, abs=0.01
    )
    first = frames[0]
    distance = np.hypot(first.x_cm - spec.lamp_cm[0], first.y_cm - spec.lamp_cm[1])
    ranks = 1 + np.floor((distance - distance.min()) / (2 * R_MIN_CM)).astype(int)
    starts = [t[np.argmax(radii[:, i] > R_MIN_CM + 1e-6)] for i in range(spec.count)]
    for rank, start in zip(ranks, starts, strict=True):
        assert start == pytest.approx((rank - 1) * spec.cycle_s / 2, abs=0.06)
    # Peak at T/2 into its cycle, then a pause of (N - 1) T / 2 before the next (eq. 3).
    nearest = int(np.argmin(distance))
    assert t[np.argmax(radii[:, nearest])] == pytest.approx(1.5, abs=0.06)
    period = spec.cycle_s * (1 + (ranks.max() - 1) / 2)
    again = t[(t > spec.cycle_s) & (radii[:, nearest] > R_MIN_CM + 1e-6)][0]
    assert again == pytest.approx(period, abs=0.06)


def test_the_blob_drifts_toward_the_lamp_at_its_speed() -> None:
    spec = BlobSpec(duration_s=100.0, fps=1.0, speed_mm_s=2.0, wander_cm=0.0, jitter_cm=0.0)
    frames = breathing_blob(spec)
    start, end = np.array(frames[0].centre_mean()), np.array(frames[-1].centre_mean())
    toward = np.subtract(spec.lamp_cm, spec.start_cm)
    toward /= np.linalg.norm(toward)
    assert float((end - start) @ toward) == pytest.approx(20.0, abs=0.3)  # cm in 100 s


def test_a_simulator_run_is_placed_on_the_field_y_flipped(tmp_path: Path) -> None:
    x = np.array([[1.0, 1.2], [1.0, 1.3]])
    y = np.array([[2.0, 2.0], [2.1, 2.0]])
    write_published_csv(tmp_path / "run.csv", 1, [0.0, 60.0], x, y, np.full_like(x, 0.09))
    frames = frames_from_run(
        read_published_csv(tmp_path / "run.csv"), Placement((1.0, 2.0), (150.0, 80.0))
    )
    assert frames[1].x_cm == pytest.approx([150.0, 180.0])
    assert frames[1].y_cm == pytest.approx([70.0, 80.0])  # world y up is picture y down
    assert frames[1].r_cm == pytest.approx([9.0, 9.0])
    # At a video's frame rate the rows are interpolated, on the run's own clock.
    every_20_s = frames_from_run(
        read_published_csv(tmp_path / "run.csv"), Placement((1.0, 2.0), (150.0, 80.0)), fps=0.05
    )
    assert [f.t_s for f in every_20_s] == pytest.approx([0.0, 20.0, 40.0, 60.0])
    assert every_20_s[1].x_cm == pytest.approx([150.0, 150.0 + 20 + 10 / 3])
    write_published_csv(tmp_path / "bare.csv", 1, [0.0], x[:1], y[:1])
    with pytest.raises(ValueError, match="no per-particle positions and radii"):
        frames_from_run(read_published_csv(tmp_path / "bare.csv"), Placement((0, 0), (0, 0)))
