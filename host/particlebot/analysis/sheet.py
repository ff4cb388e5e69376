"""What the tracker saw, drawn on the frames: outline, centroid, trail, lamp mask and the floor
grid the geometry implies (a wrong geometry shows as a grid that does not fit the floor); and a
contact sheet of a dozen such frames spread evenly over the run."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from particlebot.analysis.geometry import FloorGeometry
from particlebot.analysis.tracker import Detection, SwarmTracker
from particlebot.analysis.video import Image, VideoError, as_image

OUTLINE_BGR = (80, 255, 80)
FLAGGED_BGR = (0, 160, 255)
CENTROID_BGR = (60, 60, 255)
TRAIL_BGR = (0, 230, 255)
LAMP_BGR = (255, 200, 0)
GRID_BGR = (110, 110, 110)
GRID_STEP_CM = 50.0


def _clock(t_s: float) -> str:
    minutes, seconds = divmod(t_s, 60)
    return f"{int(minutes):d}:{seconds:04.1f}"


@dataclass
class Overlay:
    """Draws detections on native-size frames; remembers the trail of good centroids."""

    geometry: FloorGeometry
    trail_cm: list[tuple[float, float]] = field(default_factory=list)

    def _grid(self, image: Image, scale: float) -> None:
        """Lines every 50 cm over the field (or over the floor the image shows)."""
        width, height = self.geometry.image_size
        corners = self.geometry.to_floor(
            [[0, 0], [width - 1, 0], [width - 1, height - 1], [0, height - 1]]
        )
        if self.geometry.field_cm is not None:
            x0, y0, x1, y1 = 0.0, 0.0, *self.geometry.field_cm
        else:
            x0, y0 = corners.min(axis=0)
            x1, y1 = corners.max(axis=0)
        thickness = max(1, round(scale))
        xs = np.arange(math.ceil(x0 / GRID_STEP_CM) * GRID_STEP_CM, x1 + 1e-6, GRID_STEP_CM)
        ys = np.arange(math.ceil(y0 / GRID_STEP_CM) * GRID_STEP_CM, y1 + 1e-6, GRID_STEP_CM)
        for x in xs:
            line = self.geometry.to_image(np.stack([np.full(20, x), np.linspace(y0, y1, 20)], 1))
            cv2.polylines(image, [np.round(line).astype(np.int32)], False, GRID_BGR, thickness)
        for y in ys:
            line = self.geometry.to_image(np.stack([np.linspace(x0, x1, 20), np.full(20, y)], 1))
            cv2.polylines(image, [np.round(line).astype(np.int32)], False, GRID_BGR, thickness)

    def note(self, detection: Detection) -> None:
        """Every detection passes here, drawn or not, so the trail is complete."""
        if detection.quality == "ok":
            self.trail_cm.append((detection.x_cm, detection.y_cm))

    def draw(self, frame: Image, detection: Detection, tracker: SwarmTracker) -> Image:
        image = frame.copy()
        width, _ = self.geometry.image_size
        scale = max(1.0, width / 960)
        self._grid(image, scale)
        # Processing pixels back to native ones (pixel centres on integers in both).
        factor = width / tracker.size[0]
        for lamp in tracker.lamps:
            centre = (
                (lamp.centre_px[0] + 0.5) * factor - 0.5,
                (lamp.centre_px[1] + 0.5) * factor - 0.5,
            )
            cv2.circle(
                image,
                (round(centre[0]), round(centre[1])),
                round(lamp.radius_px * factor),
                LAMP_BGR,
                max(1, round(scale)),
                cv2.LINE_AA,
            )
        scenery = [
            np.round((c.astype(np.float64) + 0.5) * factor - 0.5).astype(np.int32)
            for c in tracker.scenery
        ]
        cv2.polylines(image, scenery, True, LAMP_BGR, max(1, round(scale)), cv2.LINE_AA)
        if len(self.trail_cm) > 1:
            trail = self.geometry.to_image(self.trail_cm)
            cv2.polylines(
                image,
                [np.round(trail).astype(np.int32)],
                False,
                TRAIL_BGR,
                max(1, round(scale)),
                cv2.LINE_AA,
            )
        colour = OUTLINE_BGR if detection.quality == "ok" else FLAGGED_BGR
        outlines = [
            np.round((c.astype(np.float64) + 0.5) * factor - 0.5).astype(np.int32)
            for c in detection.outlines
        ]
        cv2.polylines(image, outlines, True, colour, max(2, round(2 * scale)), cv2.LINE_AA)
        if math.isfinite(detection.x_cm):
            ((u, v),) = self.geometry.to_image([[detection.x_cm, detection.y_cm]])
            size = round(12 * scale)
            cv2.drawMarker(
                image,
                (round(u), round(v)),
                CENTROID_BGR,
                cv2.MARKER_CROSS,
                size,
                max(2, round(2 * scale)),
                cv2.LINE_AA,
            )
        text = f"{_clock(detection.t_s)}  {detection.quality}"
        if math.isfinite(detection.x_cm):
            text += f"  ({detection.x_cm:.1f}, {detection.y_cm:.1f}) cm"
        font_scale = 0.7 * scale
        origin = (round(10 * scale), round(30 * scale))
        # Dark outline under light letters: legible on the dark floor and on the lamp's glow.
        for colour, weight in (((0, 0, 0), 4 * scale), ((255, 255, 255), max(1, 1.5 * scale))):
            cv2.putText(
                image,
                text,
                origin,
                cv2.FONT_HERSHEY_SIMPLEX,
                font_scale,
                colour,
                round(weight),
                cv2.LINE_AA,
            )
        return image


class ContactSheet:
    """Annotated thumbnails spread evenly over the run, its last frame always the last panel.

    With the number of analysed frames known (the container says), the panels are chosen in
    advance; otherwise every stride-th frame is kept and, when twice too many are kept, every
    other one is dropped and the stride doubles."""

    def __init__(
        self, expected: int = 0, panels: int = 12, columns: int = 3, thumb_width: int = 480
    ) -> None:
        self.panels = panels
        self.columns = columns
        self.thumb_width = thumb_width
        self._targets = (
            {round(v) for v in np.linspace(0, expected - 1, panels)} if expected > 0 else None
        )
        self._kept: list[tuple[int, Image]] = []
        self._stride = 1

    def wants(self, ordinal: int) -> bool:
        """Whether the ordinal-th analysed frame becomes a panel: draw it and offer() it."""
        if self._targets is not None:
            return ordinal in self._targets
        return ordinal % self._stride == 0

    def offer(self, ordinal: int, drawn: Image) -> None:
        height = round(drawn.shape[0] * self.thumb_width / drawn.shape[1])
        thumb = cv2.resize(drawn, (self.thumb_width, height), interpolation=cv2.INTER_AREA)
        self._kept.append((ordinal, as_image(thumb)))
        if self._targets is None and len(self._kept) >= 2 * self.panels:
            self._kept = self._kept[::2]
            self._stride *= 2

    def end(self, last_ordinal: int, draw_last: Callable[[], Image]) -> None:
        """Makes the run's last frame the last panel (the container may have miscounted)."""
        if self._kept and self._kept[-1][0] == last_ordinal:
            return
        picks = self._picks()
        if len(picks) >= self.panels:
            self._kept.remove(picks[-1])
        self.offer(last_ordinal, draw_last())

    def _picks(self) -> list[tuple[int, Image]]:
        if len(self._kept) <= self.panels:
            return list(self._kept)
        chosen = np.linspace(0, len(self._kept) - 1, self.panels)
        return [self._kept[round(i)] for i in chosen]

    def write(self, path: Path, title: str) -> None:
        if not self._kept:
            raise VideoError("no frames for a contact sheet")
        thumbs = [thumb for _, thumb in self._picks()]
        rows = math.ceil(len(thumbs) / self.columns)
        th, tw = thumbs[0].shape[:2]
        banner = 36
        sheet = np.full((banner + rows * (th + 4), self.columns * (tw + 4), 3), 30, np.uint8)
        cv2.putText(
            sheet, title, (8, 25), cv2.FONT_HERSHEY_SIMPLEX, 0.7, (255, 255, 255), 1, cv2.LINE_AA
        )
        for k, thumb in enumerate(thumbs):
            r, c = divmod(k, self.columns)
            y, x = banner + r * (th + 4) + 2, c * (tw + 4) + 2
            sheet[y : y + th, x : x + tw] = thumb
        if not cv2.imwrite(str(path), sheet):
            raise VideoError(f"cannot write {path}")
