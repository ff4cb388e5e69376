"""The swarm's region and centroid in every frame: SI S6's pipeline (grayscale, edges,
binarisation, lamp suppression, morphology, perimeter, centroid) made robust.

Why edges and not brightness: the lamp lights the floor around it more than the room lights the
particles far from it, so no single grey level separates swarm from floor, but the glow changes
slowly while every particle has a sharp rim. Edges stronger than the floor's noise (measured in
every frame) mark the particles; closing joins neighbours; the outer perimeter, filled, is the
swarm's region. The lamp's head is the one sharp bright thing that does not move: its saturated
core, grown until its rim's edges end, is masked out. Specks smaller than part of a particle are
dropped, and the region kept from frame to frame is the one where the swarm was.

The centroid is the area centroid of the region's outline mapped to the floor (not of its pixels),
so a tilted camera's perspective does not weight the near side more.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import cv2
import numpy as np
import numpy.typing as npt

from particlebot.analysis.geometry import FloorGeometry, GeometryError, polygon_area_centroid
from particlebot.analysis.synthetic import R_MAX_CM, R_MIN_CM
from particlebot.analysis.trackfile import DROPPED, OK, TrackRow
from particlebot.analysis.video import Image, VideoSource, as_image

Contour = npt.NDArray[np.int32]
Mask = npt.NDArray[np.uint8]


@dataclass(frozen=True)
class Circle:
    """A circle on the floor, cm."""

    x_cm: float
    y_cm: float
    radius_cm: float


@dataclass(frozen=True)
class TrackerSettings:
    particle_diameter_cm: float = 2 * R_MIN_CM
    """Contracted diameter: sets every size the tracker judges by."""
    process_width: int = 1280
    """Frames wider than this are shrunk first (speed; 1280 px over 285 cm is 2.2 mm a pixel)."""
    smooth_cm: float = 0.25
    """Gaussian smoothing before edges, as a length on the floor."""
    edge_noise_factor: float = 10.0
    """An edge is a gradient this many noise sigmas above the typical floor gradient."""
    min_edge: float = 1.5
    """...and at least this many grey levels per pixel."""
    contrast_noise_factor: float = 4.0
    """Foreground stands this many noise sigmas above the local floor..."""
    min_contrast: float = 4.0
    """...and at least this many grey levels..."""
    relative_contrast: float = 0.15
    """...and this part of the floor's own brightness there (the lamp's glow included)."""
    edge_cover: float = 0.25
    """A region counts when its edge pixels add up to this part of an equal-area circle's rim."""
    background_cm: float = 1.5 * 2 * R_MAX_CM
    """Width of the opening that estimates the floor: wider than an expanded particle."""
    close_cm: float = 2.5
    """Gaps narrower than this between particles' rims are bridged."""
    merge_cm: float | None = None
    """Pieces closer than this to the main region count as the swarm (default: a diameter)."""
    min_area_fraction: float = 0.4
    """Regions smaller than this part of a contracted particle are specks, not swarm."""
    lamp: Literal["auto", "none"] | Circle = "auto"
    """Find the lamp's head (auto), assume none, or mask this floor circle."""
    lamp_height_cm: float = 35.0
    """Height of the lamp's head (SI S3: 35 cm desk lamps); corrects where it is drawn."""
    saturation: int = 250
    """Grey level from which a pixel counts as burnt out (the lamp's core)."""
    ignore: tuple[Circle, ...] = ()
    """Floor circles never part of the swarm (obstacles, a reflection that moves in and out)."""
    jump_cm: float = 8.0
    """A centroid moving more than this (plus 1 cm/s) between good frames is flagged."""
    area_change: float = 0.4
    """An area this far (relative) from the recent frames' median is flagged."""
    spike_cm: float = R_MAX_CM - R_MIN_CM + 1.0
    """A centroid this far from the median of its written neighbours (two each side) is a
    one-frame spike (noise, a glare joining for a frame) and is dropped. The region itself
    sways as its particles breathe, by up to about a rim's travel (R_max - R_min: 3.9 cm
    measured on the synthetic blob sampled every 2 s), hence that plus a centimetre."""
    settle_frames: int = 3
    """After this many consecutive frames that agree with each other but jump from the last good
    one, the swarm is taken to be there (a cut in the video, a swarm that split)."""

    @property
    def merge_distance_cm(self) -> float:
        return self.particle_diameter_cm if self.merge_cm is None else self.merge_cm


@dataclass(frozen=True)
class Lamp:
    """The masked lamp head, in processing pixels, and its floor position."""

    centre_px: tuple[float, float]
    radius_px: float
    floor_cm: tuple[float, float]
    given: bool


@dataclass
class Detection:
    """One frame's result; outlines are in processing pixels."""

    t_s: float
    frame: int
    x_cm: float = math.nan
    y_cm: float = math.nan
    area_cm2: float = math.nan
    outlines: list[Contour] = field(default_factory=list)
    flags: list[str] = field(default_factory=list)

    @property
    def quality(self) -> str:
        return "+".join(self.flags) if self.flags else OK

    @property
    def dropped(self) -> bool:
        """Found, but not believed: its centroid is not written as the track."""
        return bool(DROPPED & set(self.flags))

    def row(self) -> TrackRow:
        """The frame as TRACK.csv has it: a dropped frame keeps its flags, not its centroid."""
        if self.dropped:
            return TrackRow(self.t_s, math.nan, math.nan, math.nan, self.quality, self.frame)
        return TrackRow(self.t_s, self.x_cm, self.y_cm, self.area_cm2, self.quality, self.frame)


class SwarmTracker:
    """Finds the swarm frame after frame; remembers where it was and the lamp."""

    def __init__(self, geometry: FloorGeometry, settings: TrackerSettings | None = None) -> None:
        self.settings = settings or TrackerSettings()
        width, height = geometry.image_size
        scale = min(1.0, self.settings.process_width / width)
        self.size = (max(1, round(width * scale)), max(1, round(height * scale)))
        self.geometry = geometry.resized(*self.size) if scale < 1.0 else geometry
        self.px_per_cm = 1.0 / self.geometry.cm_per_px()
        s = self.settings
        self._sigma_px = max(0.8, s.smooth_cm * self.px_per_cm)
        self._background_px = s.background_cm * self.px_per_cm
        close_px = max(3, round(s.close_cm * self.px_per_cm)) | 1
        self._close_kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (close_px, close_px))
        reach_px = max(3, round(s.particle_diameter_cm / 2 * self.px_per_cm)) | 1
        # A square (separable, fast) is as good as a disc for "near".
        self._reach_kernel = cv2.getStructuringElement(cv2.MORPH_RECT, (reach_px, reach_px))
        particle_area_cm2 = math.pi * (s.particle_diameter_cm / 2) ** 2
        self._min_area_cm2 = s.min_area_fraction * particle_area_cm2
        self._static_mask = np.zeros((self.size[1], self.size[0]), np.uint8)
        for zone in s.ignore:
            self._mask_floor_circle(self._static_mask, zone, height_cm=0.0)
        self.lamps: list[Lamp] = []
        self._lamp_mask = np.zeros_like(self._static_mask)
        self._lamp_ready = False
        self._near_lamp: Mask | None = None
        self._last_ok: Detection | None = None
        self._recent_areas: deque[float] = deque(maxlen=25)
        self._leaps: list[Detection] = []
        self._scenery_ready = False
        self.scenery: list[Contour] = []
        """Outlines (processing pixels) of what the first frame showed beside the lamp that is
        not the swarm (its foot and arm), masked from then on."""

    # -- preparation ------------------------------------------------------------------------------

    def prepare(self, frame: Image) -> Image:
        """The frame as the tracker works on it: processing size."""
        if (frame.shape[1], frame.shape[0]) != self.size:
            return as_image(cv2.resize(frame, self.size, interpolation=cv2.INTER_AREA))
        return frame

    def _lamp_geometry(self) -> FloorGeometry:
        """Where the lamp's head (not its foot) is seen, when the camera allows knowing it."""
        try:
            return self.geometry.at_height(self.settings.lamp_height_cm)
        except GeometryError:
            return self.geometry

    def _mask_floor_circle(self, mask: Mask, zone: Circle, height_cm: float) -> None:
        geometry = self._lamp_geometry() if height_cm else self.geometry
        angles = np.linspace(0, 2 * math.pi, 48, endpoint=False)
        ring = np.stack(
            [
                zone.x_cm + zone.radius_cm * np.cos(angles),
                zone.y_cm + zone.radius_cm * np.sin(angles),
            ],
            axis=1,
        )
        polygon = np.round(geometry.to_image(ring)).astype(np.int32)
        cv2.fillPoly(mask, [polygon], 255)

    def _find_lamps(self, image: Image) -> None:
        """On the first frame: the lamp's head (given, or the largest burnt-out blobs) and the
        mask over it."""
        s = self.settings
        self._lamp_ready = True
        if s.lamp == "none":
            return
        if isinstance(s.lamp, Circle):
            self._mask_floor_circle(self._lamp_mask, s.lamp, height_cm=s.lamp_height_cm)
            centre = self._lamp_geometry().to_image([[s.lamp.x_cm, s.lamp.y_cm]])[0]
            radius = s.lamp.radius_cm * self.px_per_cm
            self.lamps.append(
                Lamp((float(centre[0]), float(centre[1])), radius, (s.lamp.x_cm, s.lamp.y_cm), True)
            )
            return
        smooth, edges, _ = self.foreground(image)
        saturated = (smooth >= s.saturation).astype(np.uint8)
        count, _, stats, centres = cv2.connectedComponentsWithStats(saturated)
        min_area = math.pi * (1.5 * self.px_per_cm) ** 2
        cores = [
            (float(stats[k, cv2.CC_STAT_AREA]), float(centres[k][0]), float(centres[k][1]))
            for k in range(1, count)
            if stats[k, cv2.CC_STAT_AREA] >= min_area
        ]
        for area, cx, cy in sorted(cores, reverse=True):
            core = math.sqrt(area / math.pi)
            # The mask covers the head out to its outermost rim: the last ring that is mostly
            # edges before a stretch of floor as wide as the core (a swarm beside the lamp
            # fills only part of any ring).
            window = int(8 * core + 10)
            distance, (x0, y0, x1, y1) = self._distances(cx, cy, window)
            sharp = edges[y0:y1, x0:x1] > 0
            radius = core
            for rho in np.arange(core, window, 1.0):
                ring = (distance >= rho) & (distance < rho + 1.5)
                if ring.any() and sharp[ring].mean() >= 0.4:
                    radius = float(rho) + 1.5
                elif rho - radius > max(core, 2 * self.px_per_cm):
                    break
            radius += max(2.0, 0.5 * self.px_per_cm)
            cv2.circle(self._lamp_mask, (round(cx), round(cy)), math.ceil(radius), 255, -1)
            fx, fy = self._lamp_geometry().to_floor([[cx, cy]])[0]
            self.lamps.append(Lamp((cx, cy), radius, (float(fx), float(fy)), False))

    def _distances(
        self, cx: float, cy: float, reach: int
    ) -> tuple[npt.NDArray[np.float64], tuple[int, int, int, int]]:
        """Pixel distances from (cx, cy) over the window of that reach, and the window."""
        width, height = self.size
        x0, x1 = max(0, int(cx) - reach), min(width, int(cx) + reach + 1)
        y0, y1 = max(0, int(cy) - reach), min(height, int(cy) + reach + 1)
        vv, uu = np.mgrid[y0:y1, x0:x1]
        return np.hypot(uu - cx, vv - cy), (x0, y0, x1, y1)

    # -- one frame --------------------------------------------------------------------------------

    def _grey(self, image: Image) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """(softly smoothed, raw) grey levels of a processing-size frame."""
        grey = np.asarray(
            cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image, np.float32
        )
        return np.asarray(cv2.GaussianBlur(grey, (0, 0), 2 * self._sigma_px), np.float32), grey

    def foreground(self, image: Image) -> tuple[npt.NDArray[np.float32], Mask, Mask]:
        """(smoothed grey image, edges, bright) of a processing-size frame.

        Edges are gradients well above the floor's noise; bright is what stands out from the
        local floor (a grey opening wider than any particle estimates the floor and the lamp's
        glow on it). Thresholds come from each frame's own statistics, so exposure changes and
        compression need no new settings."""
        s = self.settings
        soft, grey = self._grey(image)
        sharp = np.asarray(cv2.GaussianBlur(grey, (0, 0), self._sigma_px), np.float32)
        gx = cv2.Scharr(sharp, cv2.CV_32F, 1, 0, scale=1 / 32)
        gy = cv2.Scharr(sharp, cv2.CV_32F, 0, 1, scale=1 / 32)
        magnitude = np.asarray(cv2.magnitude(gx, gy), np.float32)
        edges = magnitude > max(s.min_edge, _robust_level(magnitude, s.edge_noise_factor))
        # The opening runs on a shrunk copy: the floor's shading is smooth, and a kernel the size
        # of a few particles is slow at full resolution.
        width, height = self.size
        factor = max(1, int(self._background_px / 15))
        small = cv2.resize(
            soft, (max(1, width // factor), max(1, height // factor)), interpolation=cv2.INTER_AREA
        )
        kernel_px = max(3, int(self._background_px / factor)) | 1
        kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (kernel_px, kernel_px))
        floor = cv2.resize(
            cv2.morphologyEx(small, cv2.MORPH_OPEN, kernel),
            (width, height),
            interpolation=cv2.INTER_LINEAR,
        )
        lift = np.asarray(soft - floor, np.float32)
        # The floor's texture and the camera's noise grow with its brightness: near the lamp a
        # contrast that stands out on the dark floor is only the cloth's weave.
        level = max(s.min_contrast, _robust_level(lift, s.contrast_noise_factor))
        bright = lift > np.maximum(level, s.relative_contrast * floor)
        return (
            sharp,
            as_image(edges.astype(np.uint8) * 255),
            as_image(bright.astype(np.uint8) * 255),
        )

    def detect(self, frame: Image, t_s: float, index: int) -> Detection:
        image = self.prepare(frame)
        if not self._lamp_ready:
            self._find_lamps(image)
        _, edges, bright = self.foreground(image)
        blocked = cv2.bitwise_or(self._lamp_mask, self._static_mask)
        edges[blocked > 0] = 0
        bright[blocked > 0] = 0
        # Brightness only fills in between edges (a dim particle's broken rim): the floor's glow
        # and a stray light's glare are bright too, but lie outside any sharp rim, so a closing
        # (which does not grow past the rims' outer envelope) bounds it, where a dilation would
        # let a glare beside the swarm add a fringe half a particle wide.
        near_edges = cv2.morphologyEx(edges, cv2.MORPH_CLOSE, self._reach_kernel)
        foreground = cv2.bitwise_or(edges, cv2.bitwise_and(bright, near_edges))
        closed = cv2.morphologyEx(foreground, cv2.MORPH_CLOSE, self._close_kernel)
        # Only what has sharp rims is swarm: soft glare and the cloth's mottle stand out from
        # the floor too, but have next to no edges.
        count, labels, stats, _ = cv2.connectedComponentsWithStats(closed, connectivity=8)
        edge_counts = np.bincount(labels[edges > 0], minlength=count)
        keep = np.zeros(count, bool)
        for label in range(1, count):
            circumference = math.sqrt(4 * math.pi * stats[label, cv2.CC_STAT_AREA])
            keep[label] = edge_counts[label] >= self.settings.edge_cover * circumference
        closed = (keep[labels] * 255).astype(np.uint8)
        contours, _ = cv2.findContours(closed, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        pieces = []
        for contour in contours:
            if len(contour) < 3:
                continue
            area, cx, cy = polygon_area_centroid(self.geometry.to_floor(contour.reshape(-1, 2)))
            if area >= self._min_area_cm2:
                pieces.append((contour, area, cx, cy))
        detection = Detection(t_s, index)
        if not pieces:
            detection.flags.append("lost")
            return detection
        main = self._choose(pieces)
        chosen = [p for p in pieces if p is main or self._near(p[0], main[0])]
        if not self._scenery_ready:
            self._scenery_ready = True
            if self._learn_scenery([c for c in contours if len(c) >= 3], chosen):
                return self.detect(frame, t_s, index)
        total = sum(p[1] for p in chosen)
        detection.x_cm = sum(p[1] * p[2] for p in chosen) / total
        detection.y_cm = sum(p[1] * p[3] for p in chosen) / total
        detection.area_cm2 = total
        detection.outlines = [p[0] for p in chosen]
        self._judge(detection)
        self._remember(detection)
        return detection

    def _learn_scenery(
        self, contours: Sequence[Contour], swarm: Sequence[tuple[Contour, float, float, float]]
    ) -> bool:
        """On the first frame: what stands beside the lamp's head and is not the swarm (the
        lamp's foot, its arm, things on the floor under it) is scenery, masked from then on.
        A lamp's arm is no longer than its height, so only regions that reach within that of the
        head's floor point count; the swarm, which starts away from the lamp, keeps what it
        touches. Returns whether anything was masked."""
        if not self.lamps:
            return False
        s = self.settings
        reach_cm = s.lamp_height_cm + s.particle_diameter_cm / 2
        swarm_ids = {id(p[0]) for p in swarm}
        grow_px = max(3, round(1.0 * self.px_per_cm) * 2 + 1)
        grown = np.zeros_like(self._lamp_mask)
        for contour in contours:
            if id(contour) in swarm_ids:
                continue
            floor = self.geometry.to_floor(contour.reshape(-1, 2))
            for lamp in self.lamps:
                gap = np.hypot(floor[:, 0] - lamp.floor_cm[0], floor[:, 1] - lamp.floor_cm[1])
                if float(gap.min()) < reach_cm:
                    cv2.drawContours(grown, [contour], -1, 255, -1)
                    break
        if not grown.any():
            return False
        # The blurred rim of what is masked must not come back as edges.
        grown = as_image(cv2.dilate(grown, np.ones((grow_px, grow_px), np.uint8)))
        outlines, _ = cv2.findContours(grown, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        self.scenery = [np.asarray(c, np.int32) for c in outlines]
        self._lamp_mask = as_image(cv2.bitwise_or(self._lamp_mask, grown))
        self._near_lamp = None
        return True

    def _remember(self, detection: Detection) -> None:
        """What the next frames are judged against: the last frame that did not leap (a frame
        whose outline touches the lamp or the border still says where the swarm is), and the
        areas of clean frames. A leap repeated settle_frames times in agreement is believed."""
        if "jump" not in detection.flags:
            self._leaps.clear()
            if "area" not in detection.flags:
                self._last_ok = detection
            if not detection.flags:
                self._recent_areas.append(detection.area_cm2)
            return
        self._leaps.append(detection)
        if len(self._leaps) >= self.settings.settle_frames and all(
            math.hypot(d.x_cm - detection.x_cm, d.y_cm - detection.y_cm) < self.settings.jump_cm
            for d in self._leaps
        ):
            self._last_ok = detection
            self._recent_areas.clear()
            self._leaps.clear()

    def _choose(
        self, pieces: Sequence[tuple[Contour, float, float, float]]
    ) -> tuple[Contour, float, float, float]:
        """The piece where the swarm was (holding its last centroid, else nearest to it within a
        swarm's size); the largest in the first frame or when nothing is near."""
        largest = max(pieces, key=lambda p: p[1])
        last = self._last_ok
        if last is None:
            return largest
        point = self.geometry.to_image([[last.x_cm, last.y_cm]])[0]
        for piece in pieces:
            if cv2.pointPolygonTest(piece[0], (float(point[0]), float(point[1])), False) >= 0:
                return piece
        reach = math.sqrt(last.area_cm2 / math.pi) + self.settings.particle_diameter_cm
        near = [p for p in pieces if math.hypot(p[2] - last.x_cm, p[3] - last.y_cm) < reach]
        return min(
            near, key=lambda p: math.hypot(p[2] - last.x_cm, p[3] - last.y_cm), default=largest
        )

    def _near(self, contour: Contour, main: Contour) -> bool:
        a = contour.reshape(-1, 2)[:: max(1, len(contour) // 200)].astype(np.float64)
        b = main.reshape(-1, 2)[:: max(1, len(main) // 200)].astype(np.float64)
        gap_px = float(np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1)).min())
        return gap_px * self.geometry.cm_per_px() < self.settings.merge_distance_cm

    def _judge(self, detection: Detection) -> None:
        width, height = self.size
        points = np.vstack([c.reshape(-1, 2) for c in detection.outlines])
        if (
            (points[:, 0] <= 1).any()
            or (points[:, 1] <= 1).any()
            or (points[:, 0] >= width - 2).any()
            or (points[:, 1] >= height - 2).any()
        ):
            detection.flags.append("edge")
        if self.lamps:
            if self._near_lamp is None:
                self._near_lamp = as_image(cv2.dilate(self._lamp_mask, np.ones((5, 5), np.uint8)))
            near_lamp = self._near_lamp
            if near_lamp[points[:, 1], points[:, 0]].any():
                detection.flags.append("lamp")
        if len(self._recent_areas) >= 3:
            typical = float(np.median(self._recent_areas))
            if abs(detection.area_cm2 - typical) > self.settings.area_change * typical:
                detection.flags.append("area")
        last = self._last_ok
        if last is not None:
            allowed = self.settings.jump_cm + 1.0 * (detection.t_s - last.t_s)
            if math.hypot(detection.x_cm - last.x_cm, detection.y_cm - last.y_cm) > allowed:
                detection.flags.append("jump")


def _robust_level(values: npt.NDArray[np.float32], sigmas: float) -> float:
    """median + sigmas x (MAD as a normal sigma) over a sparse sample: most pixels are floor."""
    sample = values[::4, ::4]
    median = float(np.median(sample))
    return median + sigmas * 1.4826 * float(np.median(np.abs(sample - median)))


@dataclass
class TrackResult:
    detections: list[Detection] = field(default_factory=list)
    lamps: list[Lamp] = field(default_factory=list)
    frames_read: int = 0
    seconds: float = 0.0
    interrupted: bool = False
    """Ctrl-C stopped it; what was tracked until then is here."""

    def dropped(self) -> list[Detection]:
        return [d for d in self.detections if d.dropped]

    def counts(self) -> dict[str, int]:
        counts: dict[str, int] = {}
        for d in self.detections:
            for flag in d.flags or [OK]:
                counts[flag] = counts.get(flag, 0) + 1
        return counts


FrameHook = Callable[[Image, Detection, SwarmTracker], None]


def track(
    source: VideoSource,
    tracker: SwarmTracker,
    step: int = 1,
    progress: Callable[[int], None] | None = None,
    on_frame: FrameHook | None = None,
) -> TrackResult:
    """Runs the tracker over every step-th frame. progress(frames read so far); on_frame gets
    (native frame, detection, tracker), for overlays. Ctrl-C ends it early with what it has."""
    started = time.perf_counter()
    result = TrackResult(lamps=tracker.lamps)
    try:
        for index, frame in source.frames(step):
            detection = tracker.detect(frame, index / source.fps, index)
            result.detections.append(detection)
            result.frames_read = index + 1
            if on_frame is not None:
                on_frame(frame, detection, tracker)
            if progress is not None:
                progress(index + 1)
    except KeyboardInterrupt:
        result.interrupted = True
    flag_spikes(result.detections, tracker.settings.spike_cm)
    result.seconds = time.perf_counter() - started
    return result


def flag_spikes(detections: Sequence[Detection], spike_cm: float, side: int = 2) -> None:
    """Flags as 'spike' every found frame whose centroid lies further than spike_cm from the
    median of its nearest undropped neighbours (up to `side` before and after): one frame that
    noise or a glare pushed off, which the jump test (a swarm's top speed) lets through. The
    median of both sides follows a swarm that turns or speeds up."""
    kept = [d for d in detections if not d.dropped and math.isfinite(d.x_cm)]
    points = np.array([(d.x_cm, d.y_cm) for d in kept]).reshape(-1, 2)
    for k, detection in enumerate(kept):
        before = np.arange(max(0, k - side), k)
        after = np.arange(k + 1, min(len(kept), k + side + 1))
        if not len(before) or not len(after):
            continue  # a one-sided median cannot tell a swarm that moves from a spike
        neighbours = np.concatenate([before, after])
        centre = np.median(points[neighbours], axis=0)
        if math.dist(points[k], centre) > spike_cm:
            detection.flags.append("spike")
