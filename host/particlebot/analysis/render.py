"""Top-view videos of known swarms: discs on a dark floor under a lamp, seen by a slightly tilted,
noisy, blurred camera, with the true centroids written beside them (the tracker's ground truth)."""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import cv2
import numpy as np
import numpy.typing as npt

from particlebot.analysis.camera import Camera
from particlebot.analysis.synthetic import R_MAX_CM, R_MIN_CM, SwarmFrame
from particlebot.analysis.video import Image, VideoWriter
from particlebot.fileio import atomic_open

FloatImage = npt.NDArray[np.float32]

# Colours (BGR, under the room's light) of the parts seen from above: the expanding ring, the top
# plate with the photocells, the board and servo on it, the magnetic connectors on the rim.
RING_BGR = (0.55, 1.25, 0.68)
PLATE_BGR = (0.80, 1.50, 0.90)
BOARD_BGR = (0.35, 0.35, 0.40)
CONNECTOR_BGR = (0.95, 1.70, 1.10)
PLATE_RADIUS_CM = 6.5
CONNECTORS = 14
_SHIFT = 4  # cv2 drawing with 4 fractional bits: 1/16 px positions
_CIRCLE_POINTS = 72


@dataclass(frozen=True)
class Stray:
    """A static bright spot on the floor: a specular reflection, a screw, a tape mark."""

    x_cm: float
    y_cm: float
    radius_cm: float
    level: float
    """Grey level added at its middle."""
    soft: bool = False
    """A soft glare (Gaussian) instead of a sharp-edged spot."""


@dataclass(frozen=True)
class Stand:
    """A desk lamp's foot on the floor and the arm rising from it to the head: solid, sharp-edged,
    lit by the lamp itself, and as still as the head, so a tracker must keep them out of the
    swarm."""

    foot_cm: tuple[float, float]
    """Centre of the round foot on the floor."""
    foot_radius_cm: float = 9.0
    arm_width_cm: float = 2.5
    foot_level: float = 60.0
    """Grey level of the foot's metal under the room's light (brightened by the lamp above)."""
    arm_level: float = 110.0


DEFAULT_STRAYS = (
    Stray(250.0, 20.0, 1.2, 200.0),
    Stray(30.0, 140.0, 0.8, 220.0),
    Stray(120.0, 150.0, 14.0, 30.0, soft=True),
)


@dataclass(frozen=True)
class Scene:
    camera: Camera
    lamp_cm: tuple[float, float] | None = (55.0, 45.0)
    lamp_height_cm: float = 35.0
    """The desk lamp's head (SI S3: 35 cm tall)."""
    lamp_radius_cm: float = 7.0
    """Radius of the lamp head as seen from above."""
    stand: Stand | None = None
    """The lamp's foot and arm; None draws the head alone (a lamp hung from above)."""
    lamp_strength: float = 3.0
    """The lamp's illuminance at its foot, in units of the room's light."""
    flare: float = 70.0
    """Grey level of the camera's halo around the bulb."""
    floor_level: float = 20.0
    """Grey level of the blackout floor under the room's light."""
    particle_level: float = 85.0
    """Brightness of a particle under the room's light (scales the part colours)."""
    particle_height_cm: float = 0.0
    """Height of the outline the camera sees; 0 draws the discs on the floor."""
    noise_sigma: float = 3.0
    blur_px: float = 1.0
    vignetting: float = 0.15
    """Brightness lost in the image corners."""
    strays: tuple[Stray, ...] = DEFAULT_STRAYS
    seed: int = 0
    look: Literal["lab", "published"] = "lab"
    """'lab': the real robots on a dark floor under the lamp (the parts, the glow, the optics
    above). 'published': the published simulator's rendering, flat discs on a white floor
    coloured by radius (PUBLISHED_DISC_BGR), with nothing else in view."""


def published_disc_bgr(r_cm: float) -> tuple[float, float, float]:
    """The published simulator's colour of a live particle of radius r (its updateCol_k): red 30,
    green from 200 contracted to 20 expanded (squared), blue from 30 to 210 (square root)."""
    span = R_MAX_CM - R_MIN_CM
    shrink = min(max((R_MAX_CM - r_cm) / span, 0.0), 1.0)
    grow = min(max((r_cm - R_MIN_CM) / span, 0.0), 1.0)
    return (30.0 + 180.0 * math.sqrt(grow), 20.0 + 180.0 * shrink**2, 30.0)


@dataclass(frozen=True)
class Truth:
    """What the tracker should find in one frame."""

    t_s: float
    mean_x_cm: float
    mean_y_cm: float
    region_x_cm: float
    region_y_cm: float
    region_area_cm2: float

    @classmethod
    def of(cls, frame: SwarmFrame) -> Truth:
        area, rx, ry = frame.region()
        mx, my = frame.centre_mean()
        return cls(frame.t_s, mx, my, rx, ry, area)


class Renderer:
    """Draws SwarmFrames as a Scene's camera sees them; the static background is made once."""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.camera = scene.camera
        self._rng = np.random.default_rng(scene.seed)
        cv2.setRNGSeed(scene.seed)  # cv2.randn draws the sensor noise
        self._floor_of_pixel = self.camera.floor_geometry(0.0)
        self._background = self._make_background()
        self._optics = self._make_optics()  # flare added and vignetting gain, per pixel
        self._part_angles = self._rng.uniform(0, 2 * math.pi, size=4096)
        self._planes: dict[float, npt.NDArray[np.float64]] = {}
        self._unit_circle = np.stack(
            [
                np.cos(np.linspace(0, 2 * math.pi, _CIRCLE_POINTS, endpoint=False)),
                np.sin(np.linspace(0, 2 * math.pi, _CIRCLE_POINTS, endpoint=False)),
            ],
            axis=1,
        )

    # -- static parts ---------------------------------------------------------------------------

    def lamp_light(self, x_cm: npt.ArrayLike, y_cm: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Illuminance on the floor in units of the room's light: 1 + the lamp's cosine-law term."""
        x, y = np.asarray(x_cm, float), np.asarray(y_cm, float)
        if self.scene.lamp_cm is None:
            return np.ones(np.broadcast(x, y).shape)
        h = self.scene.lamp_height_cm
        rho2 = (x - self.scene.lamp_cm[0]) ** 2 + (y - self.scene.lamp_cm[1]) ** 2
        return np.asarray(1.0 + self.scene.lamp_strength * h**3 / (rho2 + h * h) ** 1.5)

    def _make_background(self) -> Image:
        width, height = self.camera.image_size
        if self.scene.look == "published":
            return np.full((height, width, 3), 255, np.uint8)  # glColor3f(1, 1, 1)
        vv, uu = np.mgrid[0:height, 0:width].astype(np.float64)
        floor = self._floor_of_pixel.to_floor(np.stack([uu.ravel(), vv.ravel()], axis=1))
        fx, fy = floor[:, 0].reshape(height, width), floor[:, 1].reshape(height, width)
        level = self.scene.floor_level * self.lamp_light(fx, fy)
        # The cloth's mottle: a few grey levels over patches of ~10 cm.
        coarse = self._rng.normal(0, 1, size=(height // 16 + 2, width // 16 + 2))
        mottle = np.asarray(cv2.resize(coarse, (width, height), interpolation=cv2.INTER_CUBIC))
        level = level * (1 + 0.08 * mottle)
        for stray in self.scene.strays:
            d2 = (fx - stray.x_cm) ** 2 + (fy - stray.y_cm) ** 2
            if stray.soft:
                level = level + stray.level * np.exp(-d2 / (2 * stray.radius_cm**2))
            else:
                edge = np.clip((stray.radius_cm - np.sqrt(d2)) / 0.3 + 0.5, 0, 1)
                level = np.maximum(level, stray.level * edge)
        stand = self.scene.stand
        if stand is not None:
            d = np.hypot(fx - stand.foot_cm[0], fy - stand.foot_cm[1])
            inside = np.clip((stand.foot_radius_cm - d) / 0.3 + 0.5, 0, 1)
            foot = stand.foot_level * self.lamp_light(*stand.foot_cm)
            level = level * (1 - inside) + foot * inside
        grey = np.clip(level, 0, 255)
        # The blackout cloth is neutral; the lamp is yellow (more red and green than blue).
        tint = np.array([0.85, 1.0, 1.08])
        return np.clip(grey[..., None] * tint, 0, 255).astype(np.uint8)

    def _make_optics(self) -> tuple[FloatImage, FloatImage]:
        width, height = self.camera.image_size
        vv, uu = np.mgrid[0:height, 0:width].astype(np.float32)
        cx, cy = (width - 1) / 2, (height - 1) / 2
        r2 = ((uu - cx) ** 2 + (vv - cy) ** 2) / (cx * cx + cy * cy)
        gain = (1 - self.scene.vignetting * r2).astype(np.float32)
        flare = np.zeros((height, width), np.float32)
        if self.scene.lamp_cm is not None and self.scene.flare > 0:
            ((bu, bv),) = self.camera.project([self.scene.lamp_cm], self.scene.lamp_height_cm)
            sigma = 14.0 / self._floor_of_pixel.cm_per_px()
            flare = self.scene.flare * np.exp(-((uu - bu) ** 2 + (vv - bv) ** 2) / (2 * sigma**2))
        return flare.astype(np.float32)[..., None], gain[..., None]

    # -- drawing --------------------------------------------------------------------------------

    def _project(self, floor_cm: npt.ArrayLike, height: float) -> npt.NDArray[np.float64]:
        matrix = self._planes.get(height)
        if matrix is None:
            matrix = self._planes[height] = self.camera.image_from_plane(height)
        p = np.asarray(floor_cm, dtype=np.float64).reshape(-1, 2)
        h = p @ matrix[:, :2].T + matrix[:, 2]
        return np.asarray(h[:, :2] / h[:, 2:3], dtype=np.float64)

    def _polygon(self, x: float, y: float, r: float, height: float) -> npt.NDArray[np.int32]:
        return self._fixed(self._project(self._unit_circle * r + (x, y), height))

    @staticmethod
    def _fixed(pixels: npt.NDArray[np.float64]) -> npt.NDArray[np.int32]:
        return np.round(pixels * (1 << _SHIFT)).astype(np.int32).reshape(-1, 1, 2)

    def _fill(
        self, canvas: Image, polygon: npt.NDArray[np.int32], colour: tuple[float, ...]
    ) -> None:
        cv2.fillPoly(canvas, [polygon], colour, cv2.LINE_AA, _SHIFT)

    def _draw_particle(self, canvas: Image, index: int, x: float, y: float, r: float) -> None:
        h = self.scene.particle_height_cm
        if self.scene.look == "published":
            self._fill(canvas, self._polygon(x, y, r, h), published_disc_bgr(r))
            return
        light = float(self.lamp_light(x, y)) * self.scene.particle_level

        def colour(bgr: tuple[float, float, float]) -> tuple[float, ...]:
            return tuple(float(min(255.0, c * light)) for c in bgr)

        self._fill(canvas, self._polygon(x, y, r, h), colour(RING_BGR))
        self._fill(canvas, self._polygon(x, y, min(r, PLATE_RADIUS_CM), h), colour(PLATE_BGR))
        angle = self._part_angles[index % len(self._part_angles)]
        c, s = math.cos(angle), math.sin(angle)
        board = np.array([[-2.5, -1.6], [2.5, -1.6], [2.5, 1.6], [-2.5, 1.6]]) @ [[c, s], [-s, c]]
        self._fill(
            canvas, self._fixed(self._project(board + np.array([x, y]), h)), colour(BOARD_BGR)
        )
        for k in range(CONNECTORS):
            a = angle + 2 * math.pi * k / CONNECTORS
            dot = self._polygon(x + (r - 0.9) * math.cos(a), y + (r - 0.9) * math.sin(a), 0.8, h)
            self._fill(canvas, dot, colour(CONNECTOR_BGR))

    def _draw_lamp(self, canvas: Image) -> None:
        if self.scene.lamp_cm is None:
            return
        x, y = self.scene.lamp_cm
        h, r = self.scene.lamp_height_cm, self.scene.lamp_radius_cm
        stand = self.scene.stand
        if stand is not None:
            # The arm: a strip from the foot's middle (on the floor) to the head (h up), its
            # ends projected at their own heights.
            fx, fy = stand.foot_cm
            along = np.array([x - fx, y - fy])
            across = np.array([-along[1], along[0]]) / max(float(np.hypot(*along)), 1e-9)
            half = across * stand.arm_width_cm / 2
            foot, head = np.array([fx, fy]), np.array([x, y])
            low = self._project([foot + half, foot - half], 0.0)
            high = self._project([head - half, head + half], h)
            self._fill(canvas, self._fixed(np.vstack([low, high])), (stand.arm_level,) * 3)
        self._fill(canvas, self._polygon(x, y, r, h), (150.0, 190.0, 205.0))
        self._fill(canvas, self._polygon(x, y, 0.6 * r, h), (255.0, 255.0, 255.0))

    def render(self, frame: SwarmFrame) -> Image:
        canvas = self._background.copy()
        for i, (x, y, r) in enumerate(zip(frame.x_cm, frame.y_cm, frame.r_cm, strict=True)):
            self._draw_particle(canvas, i, float(x), float(y), float(r))
        if self.scene.look == "published":
            return canvas
        self._draw_lamp(canvas)
        flare, gain = self._optics
        image = (canvas.astype(np.float32) + flare) * gain
        if self.scene.blur_px > 0:
            image = np.asarray(cv2.GaussianBlur(image, (0, 0), self.scene.blur_px), np.float32)
        if self.scene.noise_sigma > 0:
            noise = np.empty_like(image)
            cv2.randn(noise, np.zeros(1), np.full(1, self.scene.noise_sigma))
            image += noise
        return np.clip(image, 0, 255).astype(np.uint8)


@dataclass
class RenderResult:
    path: Path
    frames: int
    truth: list[Truth] = field(default_factory=list)


def render_video(
    frames: Iterable[SwarmFrame],
    scene: Scene,
    path: Path,
    fps: float,
    progress: Callable[[int], None] | None = None,
) -> RenderResult:
    """Writes every frame to path (.mp4 or .avi) and returns the truth of each."""
    renderer = Renderer(scene)
    result = RenderResult(path, 0)
    try:
        with VideoWriter(path, fps, scene.camera.image_size) as writer:
            for frame in frames:
                writer.write(renderer.render(frame))
                result.truth.append(Truth.of(frame))
                result.frames += 1
                if progress is not None:
                    progress(result.frames)
    except BaseException:
        # Ctrl-C or an error mid-way: a video cut short may not decode; better none at all.
        path.unlink(missing_ok=True)
        raise
    return result


TRUTH_COLUMNS = ("t_s", "mean_x_cm", "mean_y_cm", "region_x_cm", "region_y_cm", "region_area_cm2")


def write_truth(path: Path, truth: Iterable[Truth]) -> None:
    with atomic_open(path, newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(TRUTH_COLUMNS)
        for row in truth:
            writer.writerow(
                [
                    f"{row.t_s:.3f}",
                    f"{row.mean_x_cm:.3f}",
                    f"{row.mean_y_cm:.3f}",
                    f"{row.region_x_cm:.3f}",
                    f"{row.region_y_cm:.3f}",
                    f"{row.region_area_cm2:.1f}",
                ]
            )


def render_checkerboard(
    camera: Camera,
    inner_corners: tuple[int, int],
    square_cm: float,
    origin_cm: tuple[float, float],
    noise_sigma: float = 2.0,
    seed: int = 0,
) -> Image:
    """A picture of a checkerboard (white border one square wide) lying on a dark floor, as the
    camera sees it; origin_cm is its top-left inner corner."""
    width, height = camera.image_size
    canvas = np.full((height, width), 25, np.uint8)
    cols, rows = inner_corners
    x0, y0 = origin_cm[0] - 2 * square_cm, origin_cm[1] - 2 * square_cm
    outline = [
        [x0, y0],
        [x0 + (cols + 3) * square_cm, y0],
        [x0 + (cols + 3) * square_cm, y0 + (rows + 3) * square_cm],
        [x0, y0 + (rows + 3) * square_cm],
    ]
    cv2.fillPoly(canvas, [Renderer._fixed(camera.project(outline))], 235, cv2.LINE_AA, _SHIFT)
    for j in range(rows + 1):
        for i in range(cols + 1):
            if (i + j) % 2:
                continue
            sx, sy = origin_cm[0] + (i - 1) * square_cm, origin_cm[1] + (j - 1) * square_cm
            square = [
                [sx, sy],
                [sx + square_cm, sy],
                [sx + square_cm, sy + square_cm],
                [sx, sy + square_cm],
            ]
            cv2.fillPoly(canvas, [Renderer._fixed(camera.project(square))], 20, cv2.LINE_AA, _SHIFT)
    image = np.asarray(cv2.GaussianBlur(canvas.astype(np.float32), (0, 0), 0.8), np.float32)
    image += np.random.default_rng(seed).normal(0, noise_sigma, image.shape).astype(np.float32)
    return np.clip(image, 0, 255).astype(np.uint8)
