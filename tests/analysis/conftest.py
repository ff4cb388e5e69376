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
from particlebot.analysis.render import Scene, Truth, render_video
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
