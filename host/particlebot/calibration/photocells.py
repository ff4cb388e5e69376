"""Photocell calibration (SI S3): each cell's gamma (eq. 7) and gain, fitted from readings at known
light, so that eq. 14 holds for every photocell of every particle.

A photocell reading V (eq. 11) gives its resistance over the load's, rho = (1023 - V) / V. A CdS
cell follows rho = c * x^gamma, x the inverse illuminance: r^2 (m^2) under one lamp (eq. 6), or
1 / lux. Readings at two or more light levels fix gamma and c for each cell (a straight line in
log rho against log x). The firmware then turns each reading into rho' = gain * rho^(1 / gamma)
(shared/protocol.toml: SENSOR_GAMMA_k, SENSOR_GAIN_k), and with gain = s / c^(1 / gamma) every
cell reads rho' = s * x: one law, one constant `s` for the whole fleet, which is what eq. 14 needs.
`s` (the fleet's photocell scale) is the geometric mean of the fleet's c^(1 / gamma) the first
time, so gains stay near 1, and is kept in the fleet file so that particles calibrated later,
under the same lamp, join the same law.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from particlebot.calibration.readings import Reading, Readings
from particlebot.errors import ParticlebotError
from particlebot.fleet import PHOTOCELL_UNITS, PhotocellLaw
from particlebot.protocol import PARAM_SPECS, Param
from particlebot.sim.world.light import ADC_FULL_SCALE, SENSOR_COUNT

GAMMA_PARAMS = tuple(Param(Param.SENSOR_GAMMA_0 + k) for k in range(SENSOR_COUNT))
GAIN_PARAMS = tuple(Param(Param.SENSOR_GAIN_0 + k) for k in range(SENSOR_COUNT))
MILLI = 1000
"""SENSOR_GAMMA_k and SENSOR_GAIN_k are in thousandths (shared/protocol.toml)."""
UNCHANGED_COUNTS = 3
"""Readings that span fewer counts than this over every light level did not see the light
change: the particles were not moved (or the lamp is off)."""
SCATTER_WARNING = 0.05
"""A cell whose log rho scatters more than this around its line (5 %) saw something else too."""
DISTANCE_UNIT = "m2"
"""The light level x of readings at distances: r^2 in square metres."""
LUX_UNIT = "1/lux"
assert {DISTANCE_UNIT, LUX_UNIT} == set(PHOTOCELL_UNITS)


class CalibrationError(ParticlebotError, ValueError):
    """Readings that cannot give a calibration; the message says which particle and why."""


def rho(value: float) -> float:
    """The photocell's resistance over the load's from a reading (eq. 11 solved for R_n)."""
    return (ADC_FULL_SCALE - value) / value


def reading_for(rho_value: float) -> float:
    """The reading a resistance ratio rho gives (eq. 11)."""
    return ADC_FULL_SCALE / (1 + rho_value)


def light_level(reading: Reading, lamp_height_cm: float) -> float:
    """x of the fit: r^2 in m^2 for a distance (the photocells lamp_height_cm below the lamp),
    1 / lux for a lux reading."""
    if reading.lux is not None:
        return 1 / reading.lux
    assert reading.distance_cm is not None
    return (reading.distance_cm**2 + lamp_height_cm**2) / 1e4


def level_unit(readings: Readings) -> str:
    return LUX_UNIT if readings.rows and readings.rows[0].lux is not None else DISTANCE_UNIT


def level_text(reading: Reading) -> str:
    if reading.lux is not None:
        return f"{reading.lux:g} lx"
    return f"{reading.distance_cm:g} cm"


@dataclass(frozen=True)
class CellFit:
    """rho = exp(log_c) * x^gamma for one photocell; residual: rms of log rho about the line."""

    gamma: float
    log_c: float
    residual: float
    levels: int

    @property
    def log_normalised(self) -> float:
        """ln c^(1 / gamma): the cell's rho^(1 / gamma) = c^(1 / gamma) * x."""
        return self.log_c / self.gamma


@dataclass(frozen=True)
class ParticleFit:
    """The fits of one particle's six cells (None: left out, with the reason in `skipped`)."""

    id: int
    cells: tuple[CellFit | None, ...]
    skipped: tuple[str, ...]


@dataclass(frozen=True)
class Correction:
    """SENSOR_GAMMA_k and SENSOR_GAIN_k for one particle, in thousandths."""

    id: int
    gamma_milli: tuple[int, ...]
    gain_milli: tuple[int, ...]

    def params(self) -> dict[Param, int]:
        values = dict(zip(GAMMA_PARAMS, self.gamma_milli, strict=True))
        values.update(zip(GAIN_PARAMS, self.gain_milli, strict=True))
        return values


def fit_cell(levels: np.ndarray, values: np.ndarray) -> CellFit:
    """Weighted least squares of log rho on log x. A reading's log rho is uncertain by
    1023 / (V (1023 - V)) per count, 6 times more at V = 980 than at V = 500, so each point
    weighs by the inverse square of that."""
    log_x = np.log(levels)
    log_rho = np.log((ADC_FULL_SCALE - values) / values)
    weights = (values * (ADC_FULL_SCALE - values) / ADC_FULL_SCALE) ** 2
    design = np.column_stack([np.ones_like(log_x), log_x])
    root = np.sqrt(weights)
    (log_c, gamma), *_ = np.linalg.lstsq(design * root[:, None], log_rho * root, rcond=None)
    residual = float(np.sqrt(np.mean((log_rho - log_c - gamma * log_x) ** 2)))
    return CellFit(float(gamma), float(log_c), residual, len(np.unique(levels)))


def fit_particle(rows: list[Reading], lamp_height_cm: float) -> ParticleFit:
    """Every cell of one particle; CalibrationError when its readings cannot say anything."""
    particle_id = rows[0].id
    levels = np.array([light_level(row, lamp_height_cm) for row in rows])
    distinct = sorted({level_text(row) for row in rows}, key=lambda t: float(t.split()[0]))
    if len(np.unique(np.round(levels, 9))) < 2:
        raise CalibrationError(
            f"particle {particle_id} has readings at one "
            f"{'illuminance' if rows[0].lux is not None else 'distance'} only "
            f"({distinct[0]}): the fit needs two or more"
        )
    intensities = [row.raw_intensity() for row in rows]
    known = [value for value in intensities if value is not None]
    if known and max(known) - min(known) < UNCHANGED_COUNTS:
        raise CalibrationError(
            f"particle {particle_id}'s readings hardly changed from {distinct[0]} to "
            f"{distinct[-1]} ({min(known):.0f}-{max(known):.0f}): was it moved between them?"
        )
    cells: list[CellFit | None] = []
    skipped: list[str] = []
    for k in range(SENSOR_COUNT):
        usable = [i for i, row in enumerate(rows) if row.healthy(k)]
        if len(np.unique(np.round(levels[usable], 9))) < 2:
            cells.append(None)
            skipped.append(f"A{k}: stuck or saturated at all but one light level; left as it is")
            continue
        values = np.array([rows[i].sensors[k] for i in usable])
        cells.append(fit_cell(levels[usable], values))
    if all(cell is None for cell in cells):
        raise CalibrationError(
            f"particle {particle_id}: no photocell gave usable readings (all stuck at 0 or 1023)"
        )
    return ParticleFit(particle_id, tuple(cells), tuple(skipped))


def fit_readings(readings: Readings, lamp_height_cm: float) -> list[ParticleFit]:
    """A fit per particle of the file, by id."""
    return [fit_particle(readings.of(pid), lamp_height_cm) for pid in readings.ids()]


def fleet_scale(fits: Iterable[ParticleFit]) -> float:
    """s: the geometric mean of every fitted cell's c^(1 / gamma), so gains centre on 1."""
    logs = [cell.log_normalised for fit in fits for cell in fit.cells if cell is not None]
    if not logs:
        raise CalibrationError("no photocell to calibrate")
    return math.exp(float(np.mean(logs)))


def correction(fit: ParticleFit, scale: float) -> Correction:
    """The parameters that put every cell of this particle on rho' = scale * x; CalibrationError
    when one falls outside what the firmware takes (a cell far off the others, or bad readings)."""
    gamma_spec, gain_spec = PARAM_SPECS[GAMMA_PARAMS[0]], PARAM_SPECS[GAIN_PARAMS[0]]
    gammas: list[int] = []
    gains: list[int] = []
    for k, cell in enumerate(fit.cells):
        if cell is None:
            gammas.append(gamma_spec.default)
            gains.append(gain_spec.default)
            continue
        gamma = round(cell.gamma * MILLI)
        gain = round(math.exp(math.log(scale) - cell.log_normalised) * MILLI)
        where = f"particle {fit.id}, photocell A{k}"
        if not gamma_spec.min <= gamma <= gamma_spec.max:
            raise CalibrationError(
                f"{where}: gamma {cell.gamma:.3f} is outside "
                f"{gamma_spec.min / MILLI:g}..{gamma_spec.max / MILLI:g}: check its readings "
                "(a shadow, a particle moved during a reading?)"
            )
        if not gain_spec.min <= gain <= gain_spec.max:
            raise CalibrationError(
                f"{where}: its gain would be {gain / MILLI:.3f}, outside "
                f"{gain_spec.min / MILLI:g}..{gain_spec.max / MILLI:g} of the fleet's photocell "
                f"scale {scale:.4g}: is it another kind of cell, or was another lamp used?"
            )
        gammas.append(gamma)
        gains.append(gain)
    return Correction(fit.id, tuple(gammas), tuple(gains))


def corrected_reading(raw: float, gamma_milli: int, gain_milli: int) -> float:
    """The formula the firmware follows within one count (shared/protocol.toml), in floating
    point: rho' = gain * rho^(1 / gamma), reading 1023 / (1 + rho')."""
    if not 0 < raw < ADC_FULL_SCALE:
        return raw
    return reading_for(gain_milli / MILLI * rho(raw) ** (MILLI / gamma_milli))


def corrected_intensity(reading: Reading, calibration: Correction) -> float | None:
    """What the calibrated particle's intensity would be: the mean of its healthy corrected
    readings (the firmware's own intensity is within a count of it)."""
    values = [
        corrected_reading(reading.sensors[k], calibration.gamma_milli[k], calibration.gain_milli[k])
        for k in range(SENSOR_COUNT)
        if reading.healthy(k)
    ]
    return float(np.mean(values)) if values else None


def reference_value(scale: float, reference_level: float) -> float:
    """V_x a calibrated particle reads at the reference point (x = r_x^2): 1023 / (1 + s r_x^2)."""
    return reading_for(scale * reference_level)


def scatter_notes(fits: Iterable[ParticleFit]) -> list[str]:
    """Cells whose readings stray from a power law, and cells left out."""
    notes = []
    for fit in fits:
        notes += [f"particle {fit.id}, {why}" for why in fit.skipped]
        for k, cell in enumerate(fit.cells):
            if cell is not None and cell.residual > SCATTER_WARNING:
                notes.append(
                    f"particle {fit.id}, A{k}: its readings scatter {100 * cell.residual:.0f} % "
                    "about a power law (a shadow, a hand, or the particle moved?)"
                )
    return notes


@dataclass(frozen=True)
class FleetCalibration:
    """Fits, the law they are put on, and each particle's parameters."""

    fits: tuple[ParticleFit, ...]
    law: PhotocellLaw
    corrections: Mapping[int, Correction]
    kept_law: bool
    """The fleet's law was kept (particles calibrated before keep theirs)."""


def calibrate(
    readings: Readings, lamp_height_cm: float, law: PhotocellLaw | None = None
) -> FleetCalibration:
    """Fits every particle of readings and puts it on `law` (the fleet's, kept so that particles
    calibrated before still agree), or on a new law centred on these particles."""
    unit = level_unit(readings)
    if law is not None and law.unit != unit:
        raise CalibrationError(
            f"the fleet's photocells follow a law in {law.unit}, these readings are in {unit}: "
            "calibrate every particle again with --new-law"
        )
    fits = tuple(fit_readings(readings, lamp_height_cm))
    kept = law is not None
    if law is None:
        law = PhotocellLaw(fleet_scale(fits), unit)
    corrections = {fit.id: correction(fit, law.scale) for fit in fits}
    return FleetCalibration(fits, law, corrections, kept)
