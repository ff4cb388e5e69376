"""Synthetic runs for the analysis tests: short clips rendered once per session (no binaries in
the repository), with the truth of every frame."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from particlebot.analysis.camera import Camera
from particlebot.analysis.geometry import FloorGeometry, from_field, from_points
from particlebot.analysis.render import Scene, Stand, Stray, Truth, render_video
from particlebot.analysis.synthetic import BlobSpec, breathing_blob

# Small frames keep the suite fast; 960 px over the paper's 285 cm is 3.4 px per cm, coarser than
# the C920's 1920 px, so accuracy here is a floor for what real videos get.
CLIP_SIZE = (960, 540)
FIELD_CORNERS_CM = [(0.0, 0.0), (285.0, 0.0), (285.0, 160.0), (0.0, 160.0)]
LAMP_CM = (55.0, 45.0)


@dataclass(frozen=True)
class Clip:
    path: Path
    truth: list[Truth]
    camera: Camera
    geometry: FloorGeometry
    fps: float


def render_clip(path: Path, camera: Camera, geometry: FloorGeometry, **blob: Any) -> Clip:
    """40 s of a ten-particle blob breathing (T = 3 s) and drifting 3 mm/s toward the lamp."""
    spec = replace(BlobSpec(duration_s=40.0, fps=1.5, speed_mm_s=3.0, seed=4), **blob)
    result = render_video(breathing_blob(spec), Scene(camera, lamp_cm=LAMP_CM), path, spec.fps)
    return Clip(path, result.truth, camera, geometry, spec.fps)


def marked_corners(camera: Camera) -> FloorGeometry:
    """The homography a person would get by clicking the field's taped corners (to 0.5 px)."""
    pixels = np.round(camera.project(FIELD_CORNERS_CM) * 2) / 2
    pairs = [
        ((float(u), float(v)), corner)
        for (u, v), corner in zip(pixels, FIELD_CORNERS_CM, strict=True)
    ]
    return from_points(pairs, camera.image_size)


@pytest.fixture(scope="session")
def paper_clip(tmp_path_factory: pytest.TempPathFactory) -> Clip:
    """The paper's camera, straight down over a 285x160 cm field; --field geometry."""
    camera = Camera.paper(CLIP_SIZE)
    path = tmp_path_factory.mktemp("clips") / "paper.mp4"
    return render_clip(path, camera, from_field(285.0, 160.0, CLIP_SIZE))


@pytest.fixture(scope="session")
def tilted_clip(tmp_path_factory: pytest.TempPathFactory) -> Clip:
    """The same camera tilted by about 2.5 degrees; geometry from the field's marked corners."""
    camera = Camera.paper(CLIP_SIZE, pitch_deg=2.0, roll_deg=-1.5, yaw_deg=1.0)
    path = tmp_path_factory.mktemp("clips") / "tilted.avi"
    return render_clip(path, camera, marked_corners(camera), seed=9, start_cm=(200.0, 110.0))


# A desk lamp's foot 23 cm from the point under its head, on the side the swarm comes from.
FOOT_CM = (72.0, 30.0)


@pytest.fixture(scope="session")
def lamp_stand_clip(tmp_path_factory: pytest.TempPathFactory) -> Clip:
    """A five-particle line walking 12 mm/s at a desk lamp standing on its foot, until its near
    end is a few cm from the foot: the foot, the arm and the glow must stay out of the swarm."""
    camera = Camera.paper(CLIP_SIZE)
    spec = BlobSpec(
        count=5,
        layout="line",
        start_cm=(150.0, 95.0),
        lamp_cm=LAMP_CM,
        speed_mm_s=12.0,
        duration_s=66.0,
        fps=1.0,
        seed=3,
    )
    scene = Scene(camera, lamp_cm=LAMP_CM, stand=Stand(FOOT_CM))
    path = tmp_path_factory.mktemp("clips") / "stand.mp4"
    result = render_video(breathing_blob(spec), scene, path, spec.fps)
    return Clip(path, result.truth, camera, from_field(285.0, 160.0, CLIP_SIZE), spec.fps)


@pytest.fixture(scope="session")
def rough_clip(tmp_path_factory: pytest.TempPathFactory) -> Clip:
    """A cheap camera's footage: twice the noise, heavy vignetting and blur, dimmer particles, a
    sharp light spot on the swarm's path and a soft glare beside it, and the lamp on its stand."""
    camera = Camera.paper(CLIP_SIZE)
    spec = BlobSpec(
        start_cm=(190.0, 95.0), lamp_cm=LAMP_CM, speed_mm_s=5.0, duration_s=60.0, fps=1.0, seed=5
    )
    strays = (
        Stray(150.0, 85.0, 2.0, 230.0),
        Stray(165.0, 70.0, 18.0, 45.0, soft=True),
        Stray(30.0, 140.0, 0.8, 220.0),
    )
    scene = Scene(
        camera,
        lamp_cm=LAMP_CM,
        stand=Stand(FOOT_CM),
        noise_sigma=6.0,
        blur_px=1.8,
        vignetting=0.4,
        strays=strays,
        particle_level=70.0,
    )
    # MJPEG in an AVI, frame by frame as many lab cameras record: through H.264 at the writer's
    # crf 23 the same scene's noise turns into blocks and its worst frame tracks 3.2 cm off
    # (docs/analysis.md says so beside the figures).
    path = tmp_path_factory.mktemp("clips") / "rough.avi"
    result = render_video(breathing_blob(spec), scene, path, spec.fps)
    return Clip(path, result.truth, camera, from_field(285.0, 160.0, CLIP_SIZE), spec.fps)
