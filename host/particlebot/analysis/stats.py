"""Table S2 from a centroid series: sample it every 30 s, put the origin at the first sample and
the lamp on +y, test the y steps with a one-tailed t-test, and give the speeds.

What the numbers mean (SI S6 and Table S2 read together; the SI does not spell out the formulas):
- a step is the centroid's displacement along +y (toward the lamp) over one interval;
- the t-test asks whether the mean step is greater than zero (H0: random motion, mean zero);
- average speed = mean step / interval, the very quantity the t-test is about; peak speed = the
  largest step / interval;
- in % of the minimum diameter per cycle: speed x cycle period / contracted diameter x 100. The
  cycle is the period at which each particle repeats its expansion and contraction, pause
  included: S6 calls 30 s "approximately 3.5 cycles", i.e. 8.6 s, where T alone (3 s in the
  paper's tests) would make it 10; and the published simulator's 12 s cycle (rise 2 s, fall
  2 s, pause 8 s) turns Table S3's mm/s into Table S4's %/cycle exactly (1.24 mm/s x 12 s =
  14.9 mm = 9.6 % of 155 mm). mm/s needs no cycle at all.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from scipy import stats as scipy_stats

from particlebot.analysis.sources import CentroidSeries, SourceError, median_spacing_s
from particlebot.analysis.synthetic import R_MIN_CM

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

DEFAULT_INTERVAL_S = 30.0
# The paper's experiments: T = 3 s (150 servo steps of 20 ms, S7) plus the pause of eq. 3 for a
# five-particle wave, (5 - 1) x T / 2 = 6 s; matches S6's "30 s, approximately 3.5 cycles".
EXPERIMENT_CYCLE_S = 9.0
EXPERIMENT_CYCLE_FROM = "the paper's experiments: T 3 s + pause 6 s"


@dataclass(frozen=True)
class StatsSettings:
    interval_s: float = DEFAULT_INTERVAL_S
    cycle_s: float | None = None
    """None: the source's own cycle, else EXPERIMENT_CYCLE_S."""
    min_diameter_cm: float = 2 * R_MIN_CM
    lamp_cm: tuple[float, float] | None = None
    """Overrides the source's lamp; in the source's coordinates (cm)."""
    average_s: float = 0.0
    """Average the centroid over this window around each sample time; 0 takes the centroid at
    the time itself, as S6 did. A window of one cycle cancels most of the region's lean toward
    whichever particles are expanded."""


@dataclass
class Frame:
    """The source turned into the paper's frame: origin at the first sample, lamp on +y (cm)."""

    origin_cm: tuple[float, float]
    lamp_up: tuple[float, float]
    """The unit vector toward the lamp in the source's (y-up) coordinates."""
    lamp_distance_cm: float

    def apply(self, x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
        dx, dy = x - self.origin_cm[0], y - self.origin_cm[1]
        ux, uy = self.lamp_up
        # +y toward the lamp; +x to its right, so the frame stays right-handed.
        return dx * uy - dy * ux, dx * ux + dy * uy


@dataclass
class StatsResult:
    name: str
    kind: str
    interval_s: float
    cycle_s: float
    cycle_from: str
    min_diameter_cm: float
    lamp_from: str
    lamp_distance_cm: float
    sample_t_s: FloatArray
    sample_x_cm: FloatArray
    sample_y_cm: FloatArray
    """Samples in the paper's frame; NaN where the source had no good data near the time."""
    track_x_cm: FloatArray
    track_y_cm: FloatArray
    """Every usable row of the source in the paper's frame (for the plot)."""
    step_t_s: FloatArray
    """Start of each interval that has a step."""
    steps_cm: FloatArray
    p_value: float
    notes: list[str] = field(default_factory=list)

    @property
    def steps(self) -> int:
        return len(self.steps_cm)

    @property
    def speeds_mm_s(self) -> FloatArray:
        return np.asarray(self.steps_cm * 10 / self.interval_s, dtype=np.float64)

    @property
    def average_mm_s(self) -> float:
        return float(self.speeds_mm_s.mean())

    @property
    def peak_mm_s(self) -> float:
        return float(self.speeds_mm_s.max())

    def percent_per_cycle(self, mm_s: float) -> float:
        """A speed in % of the contracted diameter per cycle."""
        return mm_s * self.cycle_s / (self.min_diameter_cm * 10) * 100

    @property
    def average_pct(self) -> float:
        return self.percent_per_cycle(self.average_mm_s)

    @property
    def peak_pct(self) -> float:
        return self.percent_per_cycle(self.peak_mm_s)

    @property
    def duration_s(self) -> float:
        return float(self.steps * self.interval_s)

    @property
    def net_y_cm(self) -> float:
        return float(self.steps_cm.sum())


def y_up(
    series: CentroidSeries, lamp: tuple[float, float] | None
) -> tuple[FloatArray, FloatArray, tuple[float, float] | None]:
    """x, y and the lamp with y pointing up (a right-handed floor seen from above)."""
    if not series.y_down:
        return series.x_cm, series.y_cm, lamp
    flipped = None if lamp is None else (lamp[0], -lamp[1])
    return series.x_cm, -series.y_cm, flipped


def sample(
    t_s: FloatArray,
    values: FloatArray,
    valid: BoolArray,
    times: FloatArray,
    tolerance_s: float,
    window_s: float = 0.0,
) -> FloatArray:
    """values at `times`, linear between valid rows, or their mean over window_s around each
    time; NaN where no valid row lies within tolerance_s of the time (a gap in the track is not
    bridged)."""
    t, v = t_s[valid], values[valid]
    if window_s > 0:
        # Half-open windows, so a window of exactly one cycle holds exactly one cycle of rows.
        lo = np.searchsorted(t, times - window_s / 2, side="left")
        hi = np.searchsorted(t, times + window_s / 2, side="left")
        sums = np.concatenate([[0.0], np.cumsum(v)])
        counts = hi - lo
        with np.errstate(invalid="ignore", divide="ignore"):
            out = (sums[hi] - sums[lo]) / counts
        out[counts == 0] = np.nan
        return np.asarray(out, dtype=np.float64)
    out = np.interp(times, t, v)
    nearest = np.abs(t[np.clip(np.searchsorted(t, times), 0, len(t) - 1)] - times)
    before = np.abs(t[np.clip(np.searchsorted(t, times) - 1, 0, len(t) - 1)] - times)
    out[np.minimum(nearest, before) > tolerance_s] = np.nan
    return np.asarray(out, dtype=np.float64)


def analyse(series: CentroidSeries, settings: StatsSettings) -> StatsResult:
    """One row of Table S2 from one source."""
    if settings.interval_s <= 0:
        raise SourceError("the sampling interval must be positive")
    valid = series.valid & np.isfinite(series.t_s)
    if valid.sum() < 2:
        raise SourceError(f"{series.name}: fewer than two usable centroids")
    notes = list(series.notes)
    lamp = settings.lamp_cm if settings.lamp_cm is not None else series.lamp_cm
    lamp_from = "given" if settings.lamp_cm is not None else series.lamp_from
    if lamp is None:
        raise SourceError(
            f"{series.name}: no lamp position in the source; give --lamp X,Y "
            f"(cm, in its coordinates{', y down the image' if series.y_down else ''})"
        )
    x, y, lamp_up_coords = y_up(series, lamp)
    assert lamp_up_coords is not None

    interval = settings.interval_s
    spacing = median_spacing_s(series)
    if spacing > interval * 1.001:
        interval = float(math.ceil(spacing / interval) * interval)
        notes.append(f"rows are {spacing:g} s apart: sampled every {interval:g} s instead")
    t_valid = series.t_s[valid]
    # With averaging, the first and last windows must lie inside the data: a window cut short
    # at the start would lean toward wherever the swarm was in its first half-cycle.
    half = settings.average_s / 2
    times = np.arange(t_valid[0] + half, t_valid[-1] - half + 1e-9, interval)
    if len(times) < 3:
        raise SourceError(
            f"{series.name}: {t_valid[-1] - t_valid[0]:.0f} s of usable data gives fewer than "
            f"two {interval:g} s intervals"
        )
    tolerance = max(2.5 * spacing, 0.1 * interval)
    sx = sample(series.t_s, x, valid, times, tolerance, settings.average_s)
    sy = sample(series.t_s, y, valid, times, tolerance, settings.average_s)
    if not np.isfinite(sx[0]):
        raise SourceError(f"{series.name}: no good centroid at the first sample")
    origin = (float(sx[0]), float(sy[0]))
    to_lamp = np.array(lamp_up_coords) - np.array(origin)
    distance = float(np.hypot(*to_lamp))
    if distance < 1e-6:
        raise SourceError(f"{series.name}: the lamp sits on the first centroid")
    frame = Frame(origin, (float(to_lamp[0] / distance), float(to_lamp[1] / distance)), distance)
    px, py = frame.apply(sx, sy)
    tx, ty = frame.apply(x[valid], y[valid])

    have = np.isfinite(py)
    both = have[:-1] & have[1:]
    steps = (py[1:] - py[:-1])[both]
    missing = int((~both).sum())
    if missing:
        notes.append(f"{missing} of {len(both)} intervals had no good centroid at an end")
    if len(steps) < 2:
        raise SourceError(f"{series.name}: fewer than two intervals with good centroids")
    if float(np.std(steps)) == 0.0:
        p_value = 0.0 if steps[0] > 0 else 1.0
        notes.append("every step is the same: the t-test is degenerate")
    else:
        p_value = float(scipy_stats.ttest_1samp(steps, 0.0, alternative="greater").pvalue)

    cycle = settings.cycle_s
    cycle_from = "given"
    if cycle is None:
        cycle, cycle_from = (
            (series.cycle_s, series.cycle_from)
            if series.cycle_s is not None
            else (EXPERIMENT_CYCLE_S, EXPERIMENT_CYCLE_FROM)
        )
    return StatsResult(
        name=series.name,
        kind=series.kind,
        interval_s=interval,
        cycle_s=cycle,
        cycle_from=cycle_from,
        min_diameter_cm=settings.min_diameter_cm,
        lamp_from=lamp_from,
        lamp_distance_cm=distance,
        sample_t_s=times - times[0],
        sample_x_cm=px,
        sample_y_cm=py,
        track_x_cm=tx,
        track_y_cm=ty,
        step_t_s=(times[:-1] - times[0])[both],
        steps_cm=steps,
        p_value=p_value,
        notes=notes,
    )
