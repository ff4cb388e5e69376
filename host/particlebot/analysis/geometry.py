"""Camera geometry: which floor point each image pixel shows, as one homography.

Floor coordinates are centimetres from the field's top-left corner as the camera sees it, x to the
right and y down the image (the TRACK.csv convention). Pixel coordinates put pixel centres on
integers, so the image's left edge is u = -0.5 (OpenCV's drawing and remapping convention).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import cv2
import numpy as np
import numpy.typing as npt

from particlebot.errors import ParticlebotError

FloatArray = npt.NDArray[np.float64]
Matrix = npt.NDArray[np.float64]

# The paper's camera: a C920 225 cm above the floor covering about 285 x 160 cm (SI S3).
PAPER_FIELD_CM = (285.0, 160.0)
PAPER_CAMERA_HEIGHT_CM = 225.0


class GeometryError(ParticlebotError, ValueError):
    """The geometry cannot be built from what was given (degenerate points, no board found...)."""


@dataclass(frozen=True)
class FloorGeometry:
    """Maps image pixels of one resolution to floor centimetres on one plane."""

    floor_from_image: Matrix
    """3x3 homography: floor (x, y, 1) ~ H @ (u, v, 1)."""
    image_size: tuple[int, int]
    """(width, height) in pixels of the images this geometry is for."""
    description: str
    """How it was made, for CSV headers and messages."""
    field_cm: tuple[float, float] | None = None
    """The field's size when the geometry was given as one; its rectangle starts at (0, 0)."""
    nadir_cm: tuple[float, float] | None = None
    """The floor point straight below the camera, when known (a camera looking straight down)."""
    camera_height_cm: float | None = None
    """The lens's height above the floor, when known; with nadir_cm it undoes parallax."""
    residual_cm: float | None = None
    """RMS distance between the marked floor points and where this geometry puts them."""

    @property
    def image_from_floor(self) -> Matrix:
        return np.asarray(np.linalg.inv(self.floor_from_image), dtype=np.float64)

    def to_floor(self, pixels: npt.ArrayLike) -> FloatArray:
        """(N, 2) pixel coordinates to (N, 2) floor centimetres."""
        return _apply(self.floor_from_image, pixels)

    def to_image(self, floor_cm: npt.ArrayLike) -> FloatArray:
        """(N, 2) floor centimetres to (N, 2) pixel coordinates."""
        return _apply(self.image_from_floor, floor_cm)

    def cm_per_px(self) -> float:
        """Length on the floor of one pixel at the image centre (geometric mean of both axes)."""
        w, h = self.image_size
        centre = np.array([[(w - 1) / 2, (h - 1) / 2]])
        p0 = self.to_floor(centre)[0]
        dx = self.to_floor(centre + np.array([[1.0, 0.0]]))[0] - p0
        dy = self.to_floor(centre + np.array([[0.0, 1.0]]))[0] - p0
        return math.sqrt(abs(dx[0] * dy[1] - dx[1] * dy[0]))

    def resized(self, width: int, height: int) -> FloorGeometry:
        """The same geometry for the images resized to width x height (processing scale)."""
        w, h = self.image_size
        sx, sy = w / width, h / height
        # A pixel centre u' of the resized image lies at u = (u' + 0.5) * sx - 0.5 in the original.
        native_from_resized = np.array(
            [[sx, 0.0, 0.5 * sx - 0.5], [0.0, sy, 0.5 * sy - 0.5], [0.0, 0.0, 1.0]]
        )
        return replace(
            self,
            floor_from_image=self.floor_from_image @ native_from_resized,
            image_size=(width, height),
        )

    def at_height(self, height_cm: float) -> FloorGeometry:
        """The geometry of the plane height_cm above the floor, in floor coordinates of the point
        below: what the outline of a body that tall shows. Needs the camera's nadir and height:
        the lens sees a point at height h where it would see the floor point H/(H-h) times as far
        from the nadir, whatever its tilt."""
        if height_cm == 0:
            return self
        camera_height_cm = self.camera_height_cm
        if self.nadir_cm is None or camera_height_cm is None:
            raise GeometryError("a height above the floor needs the camera's height and nadir")
        if not 0 <= height_cm < camera_height_cm:
            raise GeometryError(
                f"target height {height_cm:g} cm must lie between the floor and the camera "
                f"({camera_height_cm:g} cm)"
            )
        k = (camera_height_cm - height_cm) / camera_height_cm
        nx, ny = self.nadir_cm
        shrink = np.array([[k, 0.0, (1 - k) * nx], [0.0, k, (1 - k) * ny], [0.0, 0.0, 1.0]])
        return replace(
            self,
            floor_from_image=shrink @ self.floor_from_image,
            description=f"{self.description}, outline {height_cm:g} cm above the floor",
        )


def _apply(matrix: Matrix, points: npt.ArrayLike) -> FloatArray:
    array = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    homogeneous = np.hstack([array, np.ones((len(array), 1))]) @ matrix.T
    return np.asarray(homogeneous[:, :2] / homogeneous[:, 2:3], dtype=np.float64)


def parse_pair(text: str, what: str, separator: str = ",") -> tuple[float, float]:
    """'285x160' or '12.5,40' to two floats; GeometryError naming `what` otherwise."""
    parts = text.lower().replace(" ", "").split(separator)
    try:
        if len(parts) != 2:
            raise ValueError
        a, b = float(parts[0]), float(parts[1])
    except ValueError:
        raise GeometryError(f"{what} must look like A{separator}B, not {text!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)):
        raise GeometryError(f"{what} must be finite numbers, not {text!r}")
    return a, b


def parse_field(text: str) -> tuple[float, float]:
    """'285x160' (cm) to (285.0, 160.0)."""
    width, height = parse_pair(text, "--field", "x")
    if width <= 0 or height <= 0:
        raise GeometryError(f"--field must be positive, not {text!r}")
    return width, height


def parse_point(text: str) -> tuple[tuple[float, float], tuple[float, float]]:
    """'U,V=X,Y' (pixel = floor cm) to ((U, V), (X, Y))."""
    if text.count("=") != 1:
        raise GeometryError(f"--point must look like U,V=X,Y (pixel=floor cm), not {text!r}")
    pixel, floor = text.split("=")
    return parse_pair(pixel, "--point pixel"), parse_pair(floor, "--point floor position")


def from_field(
    width_cm: float,
    height_cm: float,
    image_size: tuple[int, int],
    camera_height_cm: float = PAPER_CAMERA_HEIGHT_CM,
) -> FloorGeometry:
    """A camera looking straight down whose image spans exactly width_cm x height_cm."""
    w, h = image_size
    sx, sy = width_cm / w, height_cm / h
    matrix = np.array([[sx, 0.0, 0.5 * sx], [0.0, sy, 0.5 * sy], [0.0, 0.0, 1.0]])
    return FloorGeometry(
        floor_from_image=matrix,
        image_size=image_size,
        description=f"field {width_cm:g}x{height_cm:g} cm, camera straight down",
        field_cm=(width_cm, height_cm),
        nadir_cm=(width_cm / 2, height_cm / 2),
        camera_height_cm=camera_height_cm,
    )


def from_points(
    pairs: Sequence[tuple[tuple[float, float], tuple[float, float]]],
    image_size: tuple[int, int],
    description: str | None = None,
    camera_height_cm: float = PAPER_CAMERA_HEIGHT_CM,
) -> FloorGeometry:
    """A homography through four or more (pixel, floor cm) pairs (least squares beyond four).

    The nadir is taken as the floor point at the image centre: exact for a camera looking straight
    down, H·tan(tilt) off otherwise (8 cm at 2 degrees), which moves a point 35 cm up (a lamp's
    head) by less than 1.5 cm when parallax is undone."""
    if len(pairs) < 4:
        raise GeometryError(f"a homography needs at least 4 marked points, got {len(pairs)}")
    pixels = np.array([p for p, _ in pairs], dtype=np.float64)
    floor = np.array([f for _, f in pairs], dtype=np.float64)
    for name, points in (("pixel", pixels), ("floor", floor)):
        if _max_triangle_area(points) < 1e-3 * _spread(points) ** 2:
            raise GeometryError(f"the marked points' {name} positions lie on one line")
    matrix, _ = cv2.findHomography(pixels, floor, 0)
    if matrix is None or not np.all(np.isfinite(matrix)):
        raise GeometryError("no homography fits the marked points (are they in the same order?)")
    geometry = FloorGeometry(
        floor_from_image=np.asarray(matrix, dtype=np.float64),
        image_size=image_size,
        description=description or f"homography through {len(pairs)} marked floor points",
        camera_height_cm=camera_height_cm,
    )
    residual = float(np.sqrt(np.mean(np.sum((geometry.to_floor(pixels) - floor) ** 2, axis=1))))
    if not _preserves_orientation(geometry, pixels):
        raise GeometryError(
            "the marked points are mirrored between image and floor (check their order and that "
            "floor y grows down the image)"
        )
    w, h = image_size
    ((nx, ny),) = geometry.to_floor([[(w - 1) / 2, (h - 1) / 2]])
    return replace(geometry, residual_cm=residual, nadir_cm=(float(nx), float(ny)))


def _spread(points: FloatArray) -> float:
    return float(np.ptp(points, axis=0).max()) or 1.0


def _max_triangle_area(points: FloatArray) -> float:
    best = 0.0
    n = len(points)
    for i in range(n):
        for j in range(i + 1, n):
            for k in range(j + 1, n):
                a, b = points[j] - points[i], points[k] - points[i]
                best = max(best, abs(a[0] * b[1] - a[1] * b[0]) / 2)
    return best


def _preserves_orientation(geometry: FloorGeometry, pixels: FloatArray) -> bool:
    """A camera above the floor never mirrors it (floor y runs down the image like pixel v)."""
    centre = pixels.mean(axis=0)
    p0, px, py = geometry.to_floor(centre + np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]))
    a, b = px - p0, py - p0
    return bool(a[0] * b[1] - a[1] * b[0] > 0)


def find_checkerboard(image: npt.NDArray[np.uint8], inner_corners: tuple[int, int]) -> FloatArray:
    """The inner corners of a checkerboard (columns x rows), as a (rows, columns, 2) grid ordered
    so that columns run with image x and rows with image y. GeometryError if not found."""
    gray = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    cols, rows = inner_corners
    # The classic detector is quick on a clean board (and, with FAST_CHECK, quick to say there
    # is none); the sector-based one copes with blur and noise where it fails.
    flags = cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_FAST_CHECK
    found, corners = cv2.findChessboardCorners(gray, (cols, rows), flags=flags)
    if found:
        criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 0.01)
        corners = cv2.cornerSubPix(gray, corners, (5, 5), (-1, -1), criteria)
    else:
        found, corners = cv2.findChessboardCornersSB(gray, (cols, rows))
    if not found:
        raise GeometryError(
            f"no checkerboard with {cols}x{rows} inner corners found in the picture "
            "(count inner corners, not squares; the whole board must be in view)"
        )
    grid = np.asarray(corners, dtype=np.float64).reshape(rows, cols, 2)
    # The detector may start at any corner; pick the symmetry whose axes follow the image's.
    candidates = [grid, grid[:, ::-1], grid[::-1, :], grid[::-1, ::-1]]
    if cols == rows:
        candidates += [c.transpose(1, 0, 2) for c in candidates]
    for candidate in candidates:
        along = (candidate[:, -1] - candidate[:, 0]).mean(axis=0)
        across = (candidate[-1, :] - candidate[0, :]).mean(axis=0)
        if along[0] > abs(along[1]) and across[1] > abs(across[0]):
            return np.ascontiguousarray(candidate)
    raise GeometryError(
        "lay the checkerboard with its rows along the field's x axis (within 45 degrees)"
    )


def from_checkerboard(
    image: npt.NDArray[np.uint8],
    inner_corners: tuple[int, int],
    square_cm: float,
    origin_cm: tuple[float, float] = (0.0, 0.0),
) -> FloorGeometry:
    """A homography from a picture of a checkerboard lying on the floor, taken by the camera
    that filmed the run. origin_cm is the floor position of the board's top-left inner corner;
    the board's rows run along the field's x axis."""
    if square_cm <= 0:
        raise GeometryError(f"the square size must be positive, not {square_cm:g} cm")
    grid = find_checkerboard(image, inner_corners)
    rows, cols = grid.shape[:2]
    jj, ii = np.mgrid[0:rows, 0:cols]
    floor = np.stack([origin_cm[0] + ii * square_cm, origin_cm[1] + jj * square_cm], axis=-1)
    pairs = [
        ((float(p[0]), float(p[1])), (float(f[0]), float(f[1])))
        for p, f in zip(grid.reshape(-1, 2), floor.reshape(-1, 2), strict=True)
    ]
    height, width = image.shape[:2]
    return from_points(
        pairs,
        (width, height),
        description=f"checkerboard {cols}x{rows} corners of {square_cm:g} cm at "
        f"({origin_cm[0]:g}, {origin_cm[1]:g}) cm",
    )


def polygon_area_centroid(points: npt.ArrayLike) -> tuple[float, float, float]:
    """Area and centroid (area, x, y) of a simple polygon given as (N, 2) vertices."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    x, y = p[:, 0], p[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    twice_area = float(cross.sum())
    if abs(twice_area) < 1e-12:
        return 0.0, float(x.mean()), float(y.mean())
    cx = float(((x + xn) * cross).sum()) / (3 * twice_area)
    cy = float(((y + yn) * cross).sum()) / (3 * twice_area)
    return abs(twice_area) / 2, cx, cy
