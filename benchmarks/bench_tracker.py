#!/usr/bin/env python3
"""Tracker accuracy and speed on synthetic runs at the paper's camera (1920x1080, 225 cm above a
285x160 cm field): centroid error against the region's and the particles' true centroids,
frames per second, and what the error does to Table S2's numbers."""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from particlebot.analysis.camera import Camera
from particlebot.analysis.geometry import FloorGeometry, from_field, from_points
from particlebot.analysis.render import Scene, Truth, render_video
from particlebot.analysis.sources import CentroidSeries
from particlebot.analysis.stats import StatsSettings, analyse
from particlebot.analysis.synthetic import BlobSpec, breathing_blob
from particlebot.analysis.tracker import SwarmTracker, track
from particlebot.analysis.video import open_video

CORNERS = [(0.0, 0.0), (285.0, 0.0), (285.0, 160.0), (0.0, 160.0)]
LAMP = (55.0, 45.0)


@dataclass
class Case:
    name: str
    camera: Camera
    geometry: FloorGeometry


def cases(size: tuple[int, int]) -> list[Case]:
    straight = Camera.paper(size)
    tilted = Camera.paper(size, pitch_deg=2.0, roll_deg=-1.5, yaw_deg=1.0)
    clicked = np.round(tilted.project(CORNERS) * 2) / 2  # a person's clicks, to half a pixel
    return [
        Case("straight down, --field 285x160", straight, from_field(285.0, 160.0, size)),
        Case(
            "tilted 2.5 deg, 4 marked corners",
            tilted,
            from_points([(tuple(p), c) for p, c in zip(clicked, CORNERS, strict=True)], size),
        ),
    ]


def row(name: str, t: np.ndarray, x: np.ndarray, y: np.ndarray, y_down: bool = True) -> str:
    series = CentroidSeries(
        name, Path(name), "track", t, x, y, np.isfinite(x), y_down, LAMP, "bench"
    )
    single = analyse(series, StatsSettings())
    averaged = analyse(series, StatsSettings(average_s=9.0))
    return (
        f"  {name:<28} avg {single.average_mm_s:.3f} mm/s ({single.average_pct:.2f} %D/cycle), "
        f"peak {single.peak_mm_s:.3f}, p {single.p_value:.2e}; averaged over 9 s: avg "
        f"{averaged.average_mm_s:.3f}, peak {averaged.peak_mm_s:.3f}, p {averaged.p_value:.2e}"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--minutes", type=float, default=5.0, help="run length (5)")
    parser.add_argument("--fps", type=float, default=2.0, help="frames per second rendered (2)")
    parser.add_argument("--size", default="1920x1080", help="frame size (1920x1080, the C920's)")
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    assert len(size) == 2
    spec = BlobSpec(
        count=10,
        start_cm=(200.0, 110.0),
        lamp_cm=LAMP,
        speed_mm_s=0.5,
        wave_size=5,
        duration_s=args.minutes * 60,
        fps=args.fps,
        seed=11,
    )
    frames = breathing_blob(spec)
    print(
        f"{len(frames)} frames of {size[0]}x{size[1]}, {args.minutes:g} min of a 10-particle "
        "blob breathing (T = 3 s, pause 6 s: a 9 s cycle) and drifting 0.5 mm/s toward the "
        "lamp; the machine may be shared, so speeds are lower bounds"
    )
    with tempfile.TemporaryDirectory() as folder:
        for case in cases((size[0], size[1])):
            path = Path(folder) / "run.mp4"
            started = time.perf_counter()
            result = render_video(frames, Scene(case.camera, lamp_cm=LAMP), path, args.fps)
            render_s = time.perf_counter() - started
            with open_video(path) as source:
                started = time.perf_counter()
                decoded = sum(1 for _ in source.frames())
                decode_s = time.perf_counter() - started
            with open_video(path) as source:
                tracked = track(source, SwarmTracker(case.geometry))
            truth: list[Truth] = result.truth
            x = np.array([d.x_cm for d in tracked.detections])
            y = np.array([d.y_cm for d in tracked.detections])
            t = np.array([d.t_s for d in tracked.detections])
            region = np.hypot(
                x - [v.region_x_cm for v in truth], y - [v.region_y_cm for v in truth]
            )
            centres = np.hypot(x - [v.mean_x_cm for v in truth], y - [v.mean_y_cm for v in truth])
            flagged = sum(1 for d in tracked.detections if d.flags)
            print(f"\n{case.name}:")
            print(
                f"  error against the region's centroid: median {np.median(region):.2f} cm, "
                f"95th percentile {np.percentile(region, 95):.2f} cm, worst {region.max():.2f} cm"
            )
            print(
                f"  error against the mean of particle centres: median {np.median(centres):.2f} "
                f"cm, worst {centres.max():.2f} cm ({flagged} frames flagged)"
            )
            print(
                f"  tracking {len(t) / tracked.seconds:.1f} frames/s (decode + detect), decoding "
                f"alone {decoded / decode_s:.0f} frames/s, rendering {len(frames) / render_s:.1f}"
                " frames/s"
            )
            print("  Table S2 from the same run, every 30 s:")
            print(row("tracked", t, x, y))
            print(
                row(
                    "truth: region centroid",
                    t,
                    np.array([v.region_x_cm for v in truth]),
                    np.array([v.region_y_cm for v in truth]),
                )
            )
            print(
                row(
                    "truth: mean of centres",
                    t,
                    np.array([v.mean_x_cm for v in truth]),
                    np.array([v.mean_y_cm for v in truth]),
                )
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
