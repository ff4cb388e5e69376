"""A pinhole camera above the floor: what the renderer projects with and the exact geometry the
tracker's estimate is checked against.

World coordinates are floor centimetres (x right, y down the field, as in TRACK.csv) plus a height
above the floor. The camera hangs above a floor point and may be tilted a little, as a camera
clamped to a ceiling never looks exactly straight down.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from particlebot.analysis.geometry import (
    PAPER_CAMERA_HEIGHT_CM,
    PAPER_FIELD_CM,
    FloatArray,
    FloorGeometry,
    Matrix,
)


@dataclass(frozen=True)
class Camera:
    image_size: tuple[int, int]
    """(width, height) in pixels."""
    focal_px: float
    """Focal length in pixels (square pixels, principal point at the image centre)."""
    nadir_cm: tuple[float, float]
    """The floor point the camera hangs above."""
    height_cm: float
    """Height of the lens above the floor."""
    pitch_deg: float = 0.0
    """Rotation about the image's x axis (the view slides along floor y)."""
    roll_deg: float = 0.0
    """Rotation about the image's y axis (the view slides along floor x)."""
    yaw_deg: float = 0.0
    """Rotation about the optical axis."""

    @classmethod
    def paper(
        cls,
        image_size: tuple[int, int] = (1920, 1080),
        *,
        pitch_deg: float = 0.0,
        roll_deg: float = 0.0,
        yaw_deg: float = 0.0,
    ) -> Camera:
        """The SI's set-up: 225 cm above the middle of a 285 cm wide field, which fills the image
        when the camera looks straight down (160 cm tall at 16:9)."""
        width_cm, height_cm = PAPER_FIELD_CM
        return cls(
            image_size=image_size,
            focal_px=image_size[0] * PAPER_CAMERA_HEIGHT_CM / width_cm,
            nadir_cm=(width_cm / 2, height_cm / 2),
            height_cm=PAPER_CAMERA_HEIGHT_CM,
            pitch_deg=pitch_deg,
            roll_deg=roll_deg,
            yaw_deg=yaw_deg,
        )

    @property
    def intrinsics(self) -> Matrix:
        w, h = self.image_size
        return np.array(
            [[self.focal_px, 0.0, (w - 1) / 2], [0.0, self.focal_px, (h - 1) / 2], [0.0, 0.0, 1.0]]
        )

    @property
    def rotation(self) -> Matrix:
        """World-to-camera rotation applied after aligning camera axes with the field's."""
        a, b, c = (math.radians(v) for v in (self.pitch_deg, self.roll_deg, self.yaw_deg))
        rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
        ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
        rz = np.array([[math.cos(c), -math.sin(c), 0], [math.sin(c), math.cos(c), 0], [0, 0, 1]])
        return np.asarray(rz @ ry @ rx, dtype=np.float64)

    def image_from_plane(self, height_cm: float = 0.0) -> Matrix:
        """Homography from floor (x, y) of points height_cm above the floor to pixels."""
        # Camera axes before tilting: x with floor x, y with floor y, z pointing down, so a point
        # at height h lies H - h in front of the lens.
        nx, ny = self.nadir_cm
        plane = np.array([[1.0, 0.0, -nx], [0.0, 1.0, -ny], [0.0, 0.0, self.height_cm - height_cm]])
        return np.asarray(self.intrinsics @ self.rotation @ plane, dtype=np.float64)

    def project(self, floor_cm: npt.ArrayLike, height_cm: float = 0.0) -> FloatArray:
        """(N, 2) floor positions at height_cm to (N, 2) pixel coordinates."""
        p = np.asarray(floor_cm, dtype=np.float64).reshape(-1, 2)
        h = np.hstack([p, np.ones((len(p), 1))]) @ self.image_from_plane(height_cm).T
        return np.asarray(h[:, :2] / h[:, 2:3], dtype=np.float64)

    def floor_geometry(self, height_cm: float = 0.0) -> FloorGeometry:
        """The exact geometry of the plane height_cm above the floor: the tracker's ideal."""
        return FloorGeometry(
            floor_from_image=np.asarray(np.linalg.inv(self.image_from_plane(height_cm))),
            image_size=self.image_size,
            description="exact camera model",
            nadir_cm=self.nadir_cm,
            camera_height_cm=self.height_cm,
        )
