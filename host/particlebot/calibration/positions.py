"""Fig. S5 (SI S3): positions of a line of particles estimated from their readings by method A
(eqs. 14-15), against where they really were, before and after photocell calibration.

The particle nearest the lamp (right under it, in the paper) is the reference: in each trial its
own reading is V_x, at r_x^2 = D_ref^2 + h^2 (h: the lamp's height above the photocells). Every
other particle's reading V_n gives r_n^2 by eq. 14 and its floor distance D_n = sqrt(r_n^2 - h^2)
(eq. 15 when the reference is under the lamp). "Before" uses the mean of each particle's raw
photocell readings, which is the intensity an uncalibrated particle reports; "after" uses the
intensity the particle itself reported, through its calibration.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable
from dataclasses import dataclass

from particlebot.calibration.photocells import CalibrationError, rho
from particlebot.calibration.readings import Readings
from particlebot.sim.world.light import ADC_FULL_SCALE


def floor_distance_cm(
    value: float, reference_value: float, reference_cm: float, lamp_height_cm: float
) -> float:
    """D_n (cm) of a particle reading `value` (eqs. 14-15), the reference reading
    reference_value at floor distance reference_cm; 0 when it reads brighter than straight
    under the lamp could be."""
    if not 0 < value < ADC_FULL_SCALE or not 0 < reference_value < ADC_FULL_SCALE:
        return math.nan
    r_x_squared = reference_cm**2 + lamp_height_cm**2
    r_n_squared = rho(value) / rho(reference_value) * r_x_squared  # eq. 14
    return math.sqrt(max(0.0, r_n_squared - lamp_height_cm**2))


@dataclass(frozen=True)
class ParticlePositions:
    """One particle's true floor distance and its estimate in each trial (cm)."""

    id: int
    true_cm: float
    before_cm: tuple[float, ...]
    after_cm: tuple[float, ...]
    """Empty when the readings carry no intensity of the particle's own."""

    @staticmethod
    def _mean(values: tuple[float, ...]) -> float:
        return statistics.fmean(values) if values else math.nan

    @staticmethod
    def _sd(values: tuple[float, ...]) -> float:
        return statistics.stdev(values) if len(values) > 1 else 0.0

    @property
    def before_mean(self) -> float:
        return self._mean(self.before_cm)

    @property
    def before_sd(self) -> float:
        return self._sd(self.before_cm)

    @property
    def after_mean(self) -> float:
        return self._mean(self.after_cm)

    @property
    def after_sd(self) -> float:
        return self._sd(self.after_cm)


@dataclass(frozen=True)
class PositionCheck:
    """Fig. S5's numbers for a line (the reference particle first)."""

    reference_id: int
    lamp_height_cm: float
    trials: int
    particles: tuple[ParticlePositions, ...]

    def _errors(self, pick: Callable[[ParticlePositions], tuple[float, ...]]) -> list[float]:
        return [
            estimate - p.true_cm
            for p in self.particles
            if p.id != self.reference_id
            for estimate in pick(p)
        ]

    def rms_before(self) -> float:
        return _rms(self._errors(lambda p: p.before_cm))

    def rms_after(self) -> float:
        return _rms(self._errors(lambda p: p.after_cm))

    def worst_before(self) -> float:
        """The largest |mean estimate - truth| of a particle, before calibration."""
        return _worst([p.before_mean - p.true_cm for p in self.others])

    def worst_after(self) -> float:
        return _worst([p.after_mean - p.true_cm for p in self.others])

    @property
    def others(self) -> list[ParticlePositions]:
        return [p for p in self.particles if p.id != self.reference_id]

    @property
    def has_after(self) -> bool:
        return all(p.after_cm for p in self.particles)


def _rms(errors: list[float]) -> float:
    finite = [e for e in errors if math.isfinite(e)]
    return math.sqrt(statistics.fmean(e * e for e in finite)) if finite else math.nan


def _worst(errors: list[float]) -> float:
    finite = [abs(e) for e in errors if math.isfinite(e)]
    return max(finite) if finite else math.nan


def check_positions(readings: Readings, lamp_height_cm: float) -> PositionCheck:
    """Fig. S5 from a readings file of a line (one step per trial); CalibrationError when the
    file cannot be one (lux instead of distances, a particle moved between trials, a trial
    without the reference particle)."""
    rows = readings.rows
    if any(row.distance_cm is None for row in rows):
        raise CalibrationError("position estimates need readings at known distances, not lux")
    truth: dict[int, float] = {}
    for row in rows:
        assert row.distance_cm is not None
        if truth.setdefault(row.id, row.distance_cm) != row.distance_cm:
            raise CalibrationError(
                f"particle {row.id} stands at {truth[row.id]:g} and at {row.distance_cm:g} cm: "
                "a check keeps each particle in its place (a calibration's readings are no check)"
            )
    if len(truth) < 2:
        raise CalibrationError("a check needs a line of two particles or more")
    reference_id = min(truth, key=lambda pid: (truth[pid], pid))
    reference_cm = truth[reference_id]
    steps = sorted({row.step for row in rows})
    before: dict[int, list[float]] = {pid: [] for pid in truth}
    after: dict[int, list[float]] = {pid: [] for pid in truth}
    for step in steps:
        trial = {row.id: row for row in rows if row.step == step}
        ref = trial.get(reference_id)
        if ref is None:
            raise CalibrationError(
                f"trial {step} has no reading of the reference particle {reference_id}"
            )
        for pid, row in trial.items():
            for into, value, ref_value in (
                (before[pid], row.raw_intensity(), ref.raw_intensity()),
                (after[pid], row.intensity, ref.intensity),
            ):
                if value is not None and ref_value is not None:
                    into.append(floor_distance_cm(value, ref_value, reference_cm, lamp_height_cm))
    particles = tuple(
        ParticlePositions(pid, truth[pid], tuple(before[pid]), tuple(after[pid]))
        for pid in sorted(truth, key=lambda pid: (truth[pid], pid))
    )
    return PositionCheck(reference_id, lamp_height_cm, len(steps), particles)
