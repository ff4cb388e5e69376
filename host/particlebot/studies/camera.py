"""Table S3 read through the paper's camera: the published simulator's rendering camera, whose
height grows with the swarm, and pixels turned into metres with one scale for every size.

The published simulator (main.cpp of its first commit) sets, per swarm size, a densest-packing
diameter and a light factor (N up to 11: 0.591 m and 16; 101: 1.718 and 8; 1,001: 5.264 and 4;
10,001: 16.449 and 2) and hangs its rendering camera at their product, straight above the world's
origin: 9.46, 13.74, 21.06 and 32.90 m. It renders a 60-degree perspective (gluPerspective's
vertical field of view) at 1920x1080, so one metre of floor is 540 / tan(30 deg) / height =
935 / height pixels. A speed read from those videos with the scale of the 1,000-particle camera
for every size is the true speed times 21.06 / height: x2.23, x1.53, x1.00 and x0.64.

`studies.published.paper_camera_factor` is that factor (the direct reading, which the dead and
speed studies report as speed_paper_camera_mm_s); `film` measures it end to end: render
a run as the published simulator drew it, find the swarm with the project's tracker every 30 s,
convert its centroid's pixels to metres with the one scale, and compute Table S3's speed.
"""

from __future__ import annotations

import csv
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from particlebot.analysis.camera import Camera
from particlebot.analysis.render import Renderer, Scene
from particlebot.analysis.synthetic import Placement, frames_from_run
from particlebot.analysis.tracker import SwarmTracker, TrackerSettings, flag_spikes
from particlebot.sim.runs.simcsv import PublishedRun, read_published_csv
from particlebot.studies.published import (
    CAMERA_IMAGE_SIZE,
    D_MIN_M,
    ONE_SCALE_PARTICLES,
    camera_height_m,
)
from particlebot.studies.published import camera_px_per_m as px_per_m
from particlebot.studies.spec import WorldSetup

SAMPLE_S = 30.0
"""SI S6: the centroid every 30 s."""
IMAGE_SIZE = CAMERA_IMAGE_SIZE


def published_camera(particles: int) -> Camera:
    """The published camera over the world's origin, in the renderer's floor centimetres (the
    world's y axis turned down the image by the placement, as the published view has it)."""
    height_cm = camera_height_m(particles) * 100
    focal = px_per_m(camera_height_m(particles)) * camera_height_m(particles)
    return Camera(IMAGE_SIZE, focal, (0.0, 0.0), height_cm)


@dataclass(frozen=True)
class CameraReading:
    """One run filmed and tracked: its Table S3 speed three ways (mm/s)."""

    particles: int
    true_mm_s: float
    """From the simulator's own centroid (the mean of the particles' centres)."""
    tracked_mm_s: float
    """From the tracked region's centroid, with the camera's true scale."""
    paper_camera_mm_s: float
    """From the tracked centroid's pixels with the one scale: what the paper would report."""
    frames: int
    dropped: int
    """Frames the tracker found but did not believe (or lost)."""


def _speed(t_s: np.ndarray, distance: np.ndarray, skip_s: float) -> float:
    """Table S3's speed: the drop in distance to the lamp from skip_s to the end, per second."""
    good = np.isfinite(distance)
    t, d = t_s[good], distance[good]
    if len(t) < 2 or t[-1] <= skip_s:
        raise ValueError("too few tracked frames after the part left out to measure a speed")
    return float((np.interp(skip_s, t, d) - d[-1]) / (t[-1] - skip_s))


def film(
    run_csv: Path, particles: int, lamp_m: tuple[float, float], skip_s: float
) -> CameraReading:
    """Films a run's per-particle CSV (simulator frame, metres) as the published simulator drew
    it, tracks the swarm every SAMPLE_S seconds and returns the speeds. lamp_m: the lamp in the
    same frame."""
    run = read_published_csv(run_csv)
    frames = frames_from_run(run, Placement((0.0, 0.0), (0.0, 0.0)))
    frames = [f for f in frames if _on_sample(f.t_s)]
    camera = published_camera(particles)
    renderer = Renderer(Scene(camera, lamp_cm=None, look="published", strays=()))
    settings = TrackerSettings(
        particle_diameter_cm=D_MIN_M * 100, process_width=IMAGE_SIZE[0], lamp="none"
    )
    # One window over the whole video, around everywhere the swarm goes (as a person crops a
    # video to the arena): the tracker works on a few hundred pixels instead of two million.
    corners = np.vstack(
        [
            camera.project(np.stack([f.x_cm + dx * f.r_cm, f.y_cm + dy * f.r_cm], axis=1))
            for f in frames
            for dx, dy in ((-1, -1), (1, 1))
        ]
    )
    margin = 2 * D_MIN_M * px_per_m(camera_height_m(particles))
    u0, v0 = (max(0, int(c - margin)) for c in corners.min(axis=0))
    u1, v1 = (
        min(size, int(c + margin) + 1)
        for c, size in zip(corners.max(axis=0), IMAGE_SIZE, strict=True)
    )
    whole = camera.floor_geometry()
    shift = np.array([[1.0, 0.0, u0], [0.0, 1.0, v0], [0.0, 0.0, 1.0]])
    window = replace(
        whole, floor_from_image=whole.floor_from_image @ shift, image_size=(u1 - u0, v1 - v0)
    )
    tracker = SwarmTracker(window, settings)
    detections = [
        tracker.detect(renderer.render(f)[v0:v1, u0:u1], f.t_s, k) for k, f in enumerate(frames)
    ]
    flag_spikes(detections, settings.spike_cm)
    t_s = np.array([d.t_s for d in detections])
    rows = [d.row() for d in detections]
    found_cm = np.array([(row.x_cm, row.y_cm) for row in rows])
    lamp_cm = np.array(Placement((0.0, 0.0), (0.0, 0.0)).to_field(*lamp_m)).reshape(1, 2)
    # The paper's reading: the centroid and the lamp in pixels, turned into metres with one
    # scale whatever the camera's height.
    pixels = camera.project(np.nan_to_num(found_cm, nan=0.0))
    pixels[~np.isfinite(found_cm).all(axis=1)] = np.nan
    lamp_px = camera.project(lamp_cm)[0]
    one_scale = px_per_m(camera_height_m(ONE_SCALE_PARTICLES))
    paper_m = np.hypot(*(pixels - lamp_px).T) / one_scale
    tracked_m = np.hypot(*(found_cm - lamp_cm[0]).T) / 100
    true_m = np.interp(t_s, run.time_s, _distance(run, lamp_m))
    return CameraReading(
        particles=particles,
        true_mm_s=_speed(t_s, true_m, skip_s) * 1000,
        tracked_mm_s=_speed(t_s, tracked_m, skip_s) * 1000,
        paper_camera_mm_s=_speed(t_s, paper_m, skip_s) * 1000,
        frames=len(detections),
        dropped=sum(1 for row in rows if not math.isfinite(row.x_cm)),
    )


def _on_sample(t_s: float) -> bool:
    k = round(t_s / SAMPLE_S)
    return abs(t_s - k * SAMPLE_S) < 1e-6


def _distance(run: PublishedRun, lamp_m: tuple[float, float]) -> np.ndarray:
    """The simulator's centroid's distance to the lamp at each row of the run."""
    centroid = run.centroid_m
    return np.asarray(np.hypot(centroid[:, 0] - lamp_m[0], centroid[:, 1] - lamp_m[1]))


def film_setup(setup: WorldSetup, skip_s: float, folder: Path) -> CameraReading:
    """Simulates a study's run with every particle in the CSV every SAMPLE_S seconds (in folder,
    resumed when it is there), then films and tracks it."""
    from particlebot.studies import seam

    filmed = replace(setup, per_particle=True, dump_interval_s=SAMPLE_S)
    outcome = seam.simulate(filmed, folder)
    dx, dy = outcome.summary["offset_x"], outcome.summary["offset_y"]
    lamp = (setup.lamp_x + dx, setup.lamp_y + dy)
    return film(folder / "run.csv", setup.particles, lamp, skip_s)


CSV_COLUMNS = (
    "particles",
    "dead_fraction",
    "seed",
    "duration_s",
    "skip_s",
    "camera_height_m",
    "true_mm_s",
    "tracked_mm_s",
    "paper_camera_mm_s",
    "frames",
    "dropped",
)


def film_dead_runs(
    cells: list[tuple[int, float]],
    seeds: range,
    duration_s: float,
    skip_s: float,
    results: Path,
    runs: Path | None = None,
    say: Callable[[str], None] = print,
) -> list[dict[str, str]]:
    """The dead study's runs of those (particles, dead fraction) cells and seeds, filmed: each
    run's folder under runs (default results/runs; large: every particle every 30 s), one row
    per run appended to results/camera-runs.csv the moment it is measured (rows already there
    are not run again). Returns every row."""
    from particlebot.studies.definitions import STUDIES, StudyOptions

    study = STUDIES["dead"]
    options = StudyOptions(
        sizes=tuple(sorted({n for n, _ in cells})),
        values=tuple(sorted({f for _, f in cells})),
        seeds=len(seeds),
        first_seed=seeds.start,
        duration_s=duration_s,
        skip_s=skip_s,
        placement="blob",
        quick=False,
    )
    table = results / "camera-runs.csv"
    results.mkdir(parents=True, exist_ok=True)
    rows = _read_rows(table)
    done = {(r["particles"], r["dead_fraction"], r["seed"], r["duration_s"]) for r in rows}
    for n, fraction in cells:
        for seed in seeds:
            key = (str(n), f"{fraction:g}", str(seed), f"{duration_s:g}")
            if key in done:
                continue
            setup, _ = study.world(study, n, fraction, seed, options)
            folder = (runs or results / "runs") / f"n{n}-dead{fraction:g}-s{seed}-{duration_s:g}s"
            started = time.perf_counter()
            reading = film_setup(setup, skip_s, folder)
            row = dict(
                zip(
                    CSV_COLUMNS,
                    (
                        *key[:3],
                        key[3],
                        f"{skip_s:g}",
                        f"{camera_height_m(n):.3f}",
                        f"{reading.true_mm_s:.6g}",
                        f"{reading.tracked_mm_s:.6g}",
                        f"{reading.paper_camera_mm_s:.6g}",
                        str(reading.frames),
                        str(reading.dropped),
                    ),
                    strict=True,
                )
            )
            _append_row(table, row)
            rows.append(row)
            say(
                f"n={n} dead={fraction:g} seed={seed}: true {reading.true_mm_s:.3f}, tracked "
                f"{reading.tracked_mm_s:.3f}, paper camera {reading.paper_camera_mm_s:.3f} mm/s "
                f"({reading.dropped} of {reading.frames} frames dropped; "
                f"{time.perf_counter() - started:.0f} s)"
            )
    return rows


def _read_rows(table: Path) -> list[dict[str, str]]:
    if not table.is_file():
        return []
    with table.open(encoding="utf-8", newline="") as stream:
        return list(csv.DictReader(stream))


def _append_row(table: Path, row: dict[str, str]) -> None:
    new = not table.is_file()
    with table.open("a", encoding="utf-8", newline="") as stream:
        writer = csv.DictWriter(stream, CSV_COLUMNS)
        if new:
            writer.writeheader()
        writer.writerow(row)
