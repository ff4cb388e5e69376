"""Swarms whose every disc is known: what the renderer draws and the tracker is checked against.

A `SwarmFrame` is one instant: time and every particle's centre and radius in floor centimetres
(the field's frame: x right, y down the image). Frames come from `breathing_blob` (a plausible
swarm creeping toward a lamp, made up here) or from a simulator run in the published CSV format
(`frames_from_run`), so the same renderer serves both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import cv2
import numpy as np
import numpy.typing as npt

from particlebot.protocol import PARAM_SPECS, Param
from particlebot.sim.runs.simcsv import PublishedRun

FloatArray = npt.NDArray[np.float64]

# The firmware's radii (micrometres in the parameter table) in centimetres.
R_MIN_CM = PARAM_SPECS[Param.RADIUS_MIN_UM].default / 1e4
R_MAX_CM = PARAM_SPECS[Param.RADIUS_MAX_UM].default / 1e4

# Raster step of the ground-truth region: 1 mm leaves the union's centroid within ~0.01 cm.
TRUTH_STEP_CM = 0.1


@dataclass(frozen=True)
class SwarmFrame:
    t_s: float
    x_cm: FloatArray
    y_cm: FloatArray
    r_cm: FloatArray

    def centre_mean(self) -> tuple[float, float]:
        """The swarm's centroid as point masses: the mean of the particles' centres."""
        return float(self.x_cm.mean()), float(self.y_cm.mean())

    def region(self) -> tuple[float, float, float]:
        """(area cm², x, y) of the region the discs cover, enclosed gaps filled: the region S6's
        pipeline measures, which leans toward expanded particles."""
        step = TRUTH_STEP_CM
        x0 = float((self.x_cm - self.r_cm).min()) - 2 * step
        y0 = float((self.y_cm - self.r_cm).min()) - 2 * step
        width = math.ceil((float((self.x_cm + self.r_cm).max()) - x0) / step) + 3
        height = math.ceil((float((self.y_cm + self.r_cm).max()) - y0) / step) + 3
        mask = np.zeros((height, width), np.uint8)
        scale = 16  # cv2's 4-bit sub-pixel coordinates
        for x, y, r in zip(self.x_cm, self.y_cm, self.r_cm, strict=True):
            centre = (round((x - x0) / step * scale), round((y - y0) / step * scale))
            # cv2 fills pixels reaching up to about half a pixel past the radius; 0.4 px less
            # leaves a disc's area within 0.1 %.
            radius = round((r / step - 0.4) * scale)
            cv2.circle(mask, centre, radius, 255, -1, cv2.LINE_8, 4)
        contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        cv2.drawContours(mask, contours, -1, 255, -1)
        m = cv2.moments(mask, binaryImage=True)
        area = m["m00"] * step * step
        return area, x0 + m["m10"] / m["m00"] * step, y0 + m["m01"] / m["m00"] * step


@dataclass(frozen=True)
class BlobSpec:
    """A compact swarm breathing in a phase-delayed wave and drifting toward a lamp."""

    count: int = 10
    start_cm: tuple[float, float] = (190.0, 95.0)
    lamp_cm: tuple[float, float] = (55.0, 45.0)
    speed_mm_s: float = 1.0
    """Mean drift toward the lamp."""
    wander_cm: float = 1.5
    """Amplitude of the swarm's slow wandering about its drift."""
    jitter_cm: float = 0.4
    """Amplitude of each particle's own wandering."""
    cycle_s: float = 3.0
    """T, one expansion and contraction (eq. 4)."""
    wave_size: int | None = None
    """N of eq. 3's pause (N - 1) T/2; None: the number of distinct S_n."""
    duration_s: float = 60.0
    fps: float = 5.0
    seed: int = 1
    layout: Literal["hex", "line"] = "hex"
    """A compact hexagonal blob, or the particles in one row across the way to the lamp."""
    r_min_cm: float = R_MIN_CM
    r_max_cm: float = R_MAX_CM


def _hex_blob(count: int) -> FloatArray:
    """`count` points of a unit-spaced hexagonal lattice nearest its origin: a compact blob."""
    side = math.ceil(math.sqrt(count)) + 2
    points = [
        (i + 0.5 * (j % 2), j * math.sqrt(3) / 2)
        for i in range(-side, side + 1)
        for j in range(-side, side + 1)
    ]
    array = np.array(points)
    array -= array[np.argmin(np.hypot(array[:, 0], array[:, 1]))]
    order = np.lexsort((array[:, 0], np.hypot(array[:, 0], array[:, 1]).round(6)))
    chosen = array[order[:count]]
    return np.asarray(chosen - chosen.mean(axis=0), dtype=np.float64)


def breathing_blob(spec: BlobSpec) -> list[SwarmFrame]:
    """Frames at spec.fps of a hex-packed blob whose particles breathe by eq. 4, each delayed by
    (S_n - 1) T/2 with S_n its distance rank in contracted diameters where it starts (the
    published rule) and pausing (N - 1) T/2 between cycles (eq. 3), while the blob drifts toward
    the lamp, turns slowly and every particle wanders a little."""
    rng = np.random.default_rng(spec.seed)
    d_min = 2 * spec.r_min_cm
    start = np.asarray(spec.start_cm, dtype=np.float64)
    lamp = np.asarray(spec.lamp_cm, dtype=np.float64)
    toward = (lamp - start) / np.hypot(*(lamp - start))
    if spec.layout == "line":
        angle = math.atan2(toward[1], toward[0]) + math.pi / 2
        row = np.stack([np.arange(spec.count) - (spec.count - 1) / 2, np.zeros(spec.count)], 1)
        shape = row
    else:
        angle = rng.uniform(0, 2 * math.pi)
        shape = _hex_blob(spec.count)
    rotation = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
    relative = (shape * d_min * 1.02) @ rotation.T
    # Slow wandering of the whole swarm (20-90 s) and of each particle (5-30 s): three
    # sinusoids each.
    swarm_phase = rng.uniform(0, 2 * math.pi, size=(2, 3))
    swarm_freq = 2 * math.pi / rng.uniform(20, 90, size=(2, 3))
    own_phase = rng.uniform(0, 2 * math.pi, size=(spec.count, 2, 3))
    own_freq = 2 * math.pi / rng.uniform(5, 30, size=(spec.count, 2, 3))
    spin_rate = rng.normal(0, math.radians(2) / 60)  # a slow turn of the whole blob, rad/s

    def positions(t: float) -> FloatArray:
        wander = (np.sin(swarm_freq * t + swarm_phase).sum(axis=1) / 3) * spec.wander_cm
        own = (np.sin(own_freq * t + own_phase).sum(axis=2) / 3) * spec.jitter_cm
        centre = start + toward * spec.speed_mm_s / 10 * t + wander
        spin = spin_rate * t
        turn = np.array([[math.cos(spin), -math.sin(spin)], [math.sin(spin), math.cos(spin)]])
        return np.asarray(centre + relative @ turn.T + own, dtype=np.float64)

    distance = np.hypot(*(positions(0.0) - lamp).T)
    s_n = 1 + np.floor((distance - distance.min()) / d_min).astype(int)
    wave = int(s_n.max()) if spec.wave_size is None else spec.wave_size
    period = spec.cycle_s * (1 + (wave - 1) / 2)
    delay = (s_n - 1) * spec.cycle_s / 2
    frames = []
    for k in range(max(1, round(spec.duration_s * spec.fps) + 1)):
        t = k / spec.fps
        within = np.mod(t - delay, period)
        cycling = (t >= delay) & (within < spec.cycle_s)
        grow = 0.5 * (1 + np.sin(2 * math.pi * within / spec.cycle_s - math.pi / 2))
        radius = spec.r_min_cm + np.where(cycling, grow, 0.0) * (spec.r_max_cm - spec.r_min_cm)
        here = positions(t)
        frames.append(SwarmFrame(t, here[:, 0].copy(), here[:, 1].copy(), radius))
    return frames


@dataclass(frozen=True)
class Placement:
    """Where a simulator's world (metres, y up) lies on the filmed field (cm, y down)."""

    world_origin_m: tuple[float, float]
    """The world point drawn at field_point_cm."""
    field_point_cm: tuple[float, float]

    def to_field(self, x_m: npt.ArrayLike, y_m: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        x = (np.asarray(x_m, float) - self.world_origin_m[0]) * 100 + self.field_point_cm[0]
        y = -(np.asarray(y_m, float) - self.world_origin_m[1]) * 100 + self.field_point_cm[1]
        return x, y


def frames_from_run(
    run: PublishedRun, placement: Placement, fps: float | None = None
) -> list[SwarmFrame]:
    """One frame per row of a run with per-particle output (positions and radii), or, with fps,
    frames at that rate with centres and radii interpolated between rows (a video's clock must
    be regular; sparse rows then glide from one to the next)."""
    if run.x_m is None or run.y_m is None or run.r_m is None:
        raise ValueError(
            f"{run.path.name} has no per-particle positions and radii (turn per-particle "
            "output on in the simulator)"
        )
    times = run.time_s
    x_m, y_m, r_m = run.x_m, run.y_m, run.r_m
    if fps is not None:
        times = np.arange(run.time_s[0], run.time_s[-1] + 1e-9, 1.0 / fps)

        def resample(table: FloatArray) -> FloatArray:
            columns = [np.interp(times, run.time_s, table[:, i]) for i in range(table.shape[1])]
            return np.stack(columns, axis=1)

        x_m, y_m, r_m = resample(x_m), resample(y_m), resample(r_m)
    frames = []
    for row, t in enumerate(times):
        alive = np.isfinite(x_m[row]) & np.isfinite(y_m[row]) & np.isfinite(r_m[row])
        x, y = placement.to_field(x_m[row, alive], y_m[row, alive])
        frames.append(SwarmFrame(float(t - times[0]), x, y, r_m[row, alive] * 100))
    return frames
