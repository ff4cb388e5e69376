"""The servo of an emulated particle: the radius its pulses give, and reading a recorded pulse
train (the contracted width, expansion cycles, frame timing).

The servo the simulation assumes is the one the particle's calibration table describes: pulse
SERVO_CAL_k gives the radius R_min + k/8 (R_max - R_min), linear in between (servo_radius_um).
A table calibrated on a real particle makes that true of its servo; the default table is what a
particle ships with.

The firmware outputs one pulse per 50 Hz frame; an edge now and then comes several microseconds
late because another interrupt was running, so a single pulse can look wider or narrower than
commanded by about as much as the first steps of a cycle change it (1, 5, 13 us for a 75-step
cycle). So a cycle is found where it is unmistakable (well clear of that jitter, after a median
over three neighbouring pulses has removed lone outliers), and its start is then located by
fitting eq. 4's pulse profile to the whole rising flank, which a few late edges cannot move.
"""

from __future__ import annotations

import itertools
import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from particlebot.firmware.native import firmware_constants
from particlebot.protocol import PARAM_SPECS, Param
from particlebot.sim.particles.emulated.harness import ServoPulse


def servo_step_s() -> float:
    """One servo step (and one 50 Hz frame), as the firmware defines it."""
    return firmware_constants().servo_step_ms / 1000


def median3(widths: Sequence[float]) -> list[float]:
    """Each width replaced by the median of itself and its two neighbours (ends kept)."""
    if len(widths) < 3:
        return list(widths)
    inner = [sorted(widths[i - 1 : i + 2])[1] for i in range(1, len(widths) - 1)]
    return [widths[0], *inner, widths[-1]]


def contracted_width(pulses: Sequence[ServoPulse]) -> float:
    """The width a resting servo gets, as measured (the median pulse of a resting stretch)."""
    if not pulses:
        raise ValueError("no pulses")
    return statistics.median(p.width_us for p in pulses)


@dataclass(frozen=True)
class Burst:
    """Consecutive frames whose (filtered) pulse is wider than the contracted one: one cycle,
    a stop ramp or a wiggle. first/last index into the pulse list it was found in."""

    first: int
    last: int
    start_s: float
    """Start of the first wider pulse."""
    end_s: float
    """Start of the last wider pulse."""
    peak_us: float

    @property
    def frames(self) -> int:
        return self.last - self.first + 1


def bursts(
    pulses: Sequence[ServoPulse], contracted_us: float, threshold_us: float = 0.5
) -> list[Burst]:
    """Every stretch of frames filtered wider than contracted_us + threshold_us.

    The default threshold is half of the smallest commanded change (1 us: the first step of a
    75-step cycle), so the very first step of a cycle counts."""
    widths = median3([p.width_us for p in pulses])
    found: list[Burst] = []
    start: int | None = None
    for i, width in enumerate([*widths, contracted_us]):
        if width > contracted_us + threshold_us:
            if start is None:
                start = i
        elif start is not None:
            found.append(
                Burst(
                    first=start,
                    last=i - 1,
                    start_s=pulses[start].start_s,
                    end_s=pulses[i - 1].start_s,
                    peak_us=max(widths[start:i]),
                )
            )
            start = None
    return found


def period_errors_us(pulses: Sequence[ServoPulse]) -> list[float]:
    """Rising edge to rising edge, minus 20 ms, for each neighbouring pair."""
    step_s = servo_step_s()
    return [(b.start_s - a.start_s - step_s) * 1e6 for a, b in itertools.pairwise(pulses)]


def missed_frames(pulses: Sequence[ServoPulse]) -> int:
    """Frames without a pulse: rising edges more than one and a half frames apart."""
    missed = 0
    step_s = servo_step_s()
    for a, b in itertools.pairwise(pulses):
        gap = b.start_s - a.start_s
        if gap > 1.5 * step_s:
            missed += round(gap / step_s) - 1
    return missed


def default_servo_table() -> list[int]:
    """SERVO_CAL_0..8 as a particle ships (pulse in us at R_min + i/8 of the stroke)."""
    points = firmware_constants().servo_cal_points
    return [PARAM_SPECS[Param(int(Param.SERVO_CAL_0) + i)].default for i in range(points)]


def servo_radius_um(
    width_us: float, table: Sequence[int], r_min_um: float, r_max_um: float
) -> float:
    """The radius a servo whose true curve is `table` takes at a pulse of width_us: the table
    read backwards, linear between its points, held at its ends (the body's stops). A table may
    fall instead of rise (a servo mounted the other way round)."""
    points = len(table)
    rising = table[-1] >= table[0]
    pulses = list(table) if rising else list(reversed(table))
    position = float(np.interp(width_us, pulses, np.arange(points, dtype=float)))
    if not rising:
        position = (points - 1) - position
    return r_min_um + (r_max_um - r_min_um) * position / (points - 1)


def cycle_profile_us(steps: int, table: Sequence[int] | None = None) -> list[float]:
    """The pulse eq. 4 asks for at each step 0..steps of a cycle (R_min at both ends), through
    the calibration table (spread evenly over R_min..R_max) by linear interpolation; computed
    here in floating point, apart from the firmware's integer arithmetic."""
    table = list(table or default_servo_table())
    widths = []
    for k in range(steps + 1):
        fraction = (1 - math.cos(2 * math.pi * k / steps)) / 2  # of the stroke
        position = fraction * (len(table) - 1)
        i = min(int(position), len(table) - 2)
        widths.append(table[i] + (table[i + 1] - table[i]) * (position - i))
    return widths


def cycle_starts(
    pulses: Sequence[ServoPulse],
    steps: int,
    contracted_us: float,
    table: Sequence[int] | None = None,
    clear_us: float = 30.0,
    flank: int = 20,
) -> list[float]:
    """When each steps-step cycle in pulses began (one still going counts once its first
    `flank` steps are in): the start of the frame that carried
    its step 0, the frame before the first wider one. A cycle counts once its filtered pulses
    rise clear_us above contracted_us; the first `flank` steps of eq. 4 are then slid over the
    frames before that point and the best match (least absolute difference) marks step 0."""
    profile = cycle_profile_us(steps, table)
    rise = [w - profile[0] for w in profile[:flank]]
    widths = [p.width_us for p in pulses]
    starts = []
    for burst in bursts(pulses, contracted_us, clear_us):
        best: tuple[float, int] | None = None
        for j in range(max(0, burst.first - flank), burst.first + 1):
            window = widths[j : j + flank]
            if len(window) < flank:
                continue
            cost = sum(abs(w - contracted_us - r) for w, r in zip(window, rise, strict=True))
            if best is None or cost < best[0]:
                best = (cost, j)
        if best is not None:
            starts.append(pulses[best[1]].start_s)
    return starts
