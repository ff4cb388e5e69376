"""The photocell calibration and Fig. S5's check, done with particles: placements, readings
averaged over STATUS reports, the corrections written to the particles and to the fleet file."""

from __future__ import annotations

import datetime as dt
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO

from particlebot.calibration.photocells import (
    DISTANCE_UNIT,
    CalibrationError,
    FleetCalibration,
    calibrate,
    reference_value,
    scatter_notes,
)
from particlebot.calibration.placements import Placement, Placer, reference
from particlebot.calibration.readings import (
    Reading,
    Readings,
    ReadingsWriter,
    from_statuses,
)
from particlebot.fleet import (
    FleetError,
    FleetFileError,
    PhotocellLaw,
    load_fleet,
    timestamp,
    updating_fleet,
)
from particlebot.protocol import PARAM_SPECS, Param, State
from particlebot.swarm.api import Swarm
from particlebot.swarm.campaigns import ids_text
from particlebot.swarm.results import NotConfirmed, ParticlesMissing

REST_STATES = (State.IDLE, State.DONE)
REFERENCE_MISMATCH = 10
"""A captured V_x further than this from what the fit predicts means the reference particle was
not where the lamp's height says (or the lamp moved): worth a warning."""


@dataclass
class Bench:
    """A swarm, who places its particles, and how readings are taken."""

    swarm: Swarm
    placer: Placer
    out: TextIO
    frames: int = 5
    settle_s: float = 1.0
    """Radio time after a placement before readings count: the hand is away, readings fresh."""
    sample_timeout_s: float = 30.0

    def say(self, text: str) -> None:
        print(text, file=self.out, flush=True)

    def check_at_rest(self, ids: Sequence[int]) -> None:
        """CalibrationError if a particle is in a run (it would move, and shade the others)."""
        for particle_id in ids:
            particle = self.swarm.particle(particle_id)
            state = particle.status.state if particle and particle.status else None
            if state is not None and state not in (*REST_STATES, State.HOLDING):
                raise CalibrationError(
                    f"particle {particle_id} is {State(state).name}: STOP the swarm first"
                )

    def measure(self, placement: Placement) -> list[Reading]:
        """Has the particles placed, waits settle_s, and averages `frames` STATUS reports of
        each."""
        self.placer.place(placement)
        self.swarm.note(f"calibration, {placement.heading}: {placement.instruction}")
        self.swarm.sleep(self.settle_s)
        try:
            statuses = self.swarm.sample(placement.ids, self.frames, timeout=self.sample_timeout_s)
        except ParticlesMissing as exc:
            raise CalibrationError(f"{placement.heading}: {exc}") from None
        return [
            from_statuses(
                placement.step,
                particle_id,
                statuses[particle_id],
                distance_cm=placement.distances_cm.get(particle_id),
                lux=placement.lux,
            )
            for particle_id in placement.ids
        ]

    def measure_all(self, plan: Sequence[Placement], writer: ReadingsWriter) -> list[Reading]:
        rows: list[Reading] = []
        for placement in plan:
            taken = self.measure(placement)
            writer.write(taken)
            rows += taken
            self.say(f"  {_reading_summary(taken)}")
        return rows

    def set_all(self, particle_id: int, values: dict[Param, int]) -> None:
        """SET_PARAMs to one particle, each confirmed; CalibrationError names the first refused."""
        for param, value in values.items():
            try:
                self.swarm.set(param, value, to=particle_id)
            except NotConfirmed as exc:
                raise CalibrationError(f"writing particle {particle_id}: {exc}") from None


def _reading_summary(rows: Sequence[Reading]) -> str:
    values = [row.raw_intensity() for row in rows]
    known = [value for value in values if value is not None]
    if not known:
        return "no healthy photocell read anything"
    return (
        f"{len(rows)} particle(s), {rows[0].frames} STATUS each: raw intensity "
        f"{min(known):.0f}-{max(known):.0f}"
    )


def calibration_table(calibration: FleetCalibration) -> str:
    """Each particle's gammas and gains, one line each."""
    lines = ["  id  gamma A0-A5                         gain A0-A5                          fit"]
    for fit in calibration.fits:
        c = calibration.corrections[fit.id]
        gammas = " ".join(f"{g / 1000:5.3f}" for g in c.gamma_milli)
        gains = " ".join(f"{g / 1000:5.3f}" for g in c.gain_milli)
        scatter = max((cell.residual for cell in fit.cells if cell is not None), default=0.0)
        lines.append(f"{fit.id:>4}  {gammas}   {gains}   {100 * scatter:.1f} %")
    return "\n".join(lines)


@dataclass
class SensorOutcome:
    calibration: FleetCalibration
    readings: Readings
    written: list[int] = field(default_factory=list)
    reference_value: int | None = None
    notes: list[str] = field(default_factory=list)


def fleet_law(fleet_path: Path | None, new_law: bool) -> PhotocellLaw | None:
    """The fleet's photocell law, to calibrate onto (None: make a new one)."""
    if fleet_path is None or new_law:
        return None
    return load_fleet(fleet_path).photocells


def calibrate_sensors(
    readings: Readings,
    lamp_height_cm: float,
    *,
    bench: Bench | None,
    fleet_path: Path | None,
    new_law: bool = False,
    reference_id: int | None = None,
) -> SensorOutcome:
    """Fits the readings; with a bench, writes each particle's corrections (confirmed), has the
    reference particle put under the lamp to capture V_x (REF_VALUE, REF_DISTANCE_MM to every
    calibrated particle) and records everything in the fleet file."""
    calibration = calibrate(readings, lamp_height_cm, fleet_law(fleet_path, new_law))
    outcome = SensorOutcome(calibration, readings, notes=scatter_notes(calibration.fits))
    if bench is None:
        return outcome
    ids = sorted(calibration.corrections)
    for particle_id in ids:
        bench.set_all(particle_id, calibration.corrections[particle_id].params())
        outcome.written.append(particle_id)
    bench.say(f"Wrote SENSOR_GAMMA_0..5 and SENSOR_GAIN_0..5 to particle(s) {ids_text(ids)}.")
    if fleet_path is not None:  # what the particles hold now, whatever happens next
        outcome.notes += record_in_fleet(fleet_path, outcome, None)
    chosen = ids[0] if reference_id is None else reference_id
    if chosen not in calibration.corrections:
        raise CalibrationError(f"the reference particle {chosen} is not among those calibrated")
    (taken,) = bench.measure(reference(chosen, lamp_height_cm))
    assert taken.intensity is not None
    spec = PARAM_SPECS[Param.REF_VALUE]
    value = min(max(round(taken.intensity), spec.min), spec.max)
    outcome.reference_value = value
    line = f"Reference point: particle {chosen} reads V_x = {value}"
    if calibration.law.unit == DISTANCE_UNIT:
        expected = reference_value(calibration.law.scale, lamp_height_cm**2 / 1e4)
        line += f" (the fit expects {expected:.0f})"
        if abs(value - expected) > REFERENCE_MISMATCH:
            outcome.notes.append(
                f"V_x {value} is {abs(value - expected):.0f} counts off the fit's "
                f"{expected:.0f}: is particle {chosen} right under the lamp, "
                f"{lamp_height_cm:g} cm below it?"
            )
    bench.say(line)
    distance_mm = round(lamp_height_cm * 10)
    for particle_id in ids:
        bench.set_all(particle_id, {Param.REF_VALUE: value, Param.REF_DISTANCE_MM: distance_mm})
    bench.say(f"Wrote REF_VALUE {value} and REF_DISTANCE_MM {distance_mm} (method A) to them.")
    if fleet_path is not None:
        record_in_fleet(fleet_path, outcome, distance_mm)
    return outcome


def record_in_fleet(fleet_path: Path, outcome: SensorOutcome, distance_mm: int | None) -> list[str]:
    """The fleet's law and each particle's parameters (with method A's reference once it is
    captured: distance_mm), into the fleet file."""
    notes = []
    law = outcome.calibration.law
    try:
        with updating_fleet(fleet_path) as fleet:
            fleet.photocells = PhotocellLaw(law.scale, law.unit, timestamp())
            for particle_id, correction in outcome.calibration.corrections.items():
                record = fleet.get(particle_id)
                if record is None:
                    notes.append(f"particle {particle_id} is not in {fleet_path}: not recorded")
                    continue
                values = {param.name: value for param, value in correction.params().items()}
                record.calibration.update(values)
                if outcome.reference_value is not None and distance_mm is not None:
                    record.calibration[Param.REF_VALUE.name] = outcome.reference_value
                    record.calibration[Param.REF_DISTANCE_MM.name] = distance_mm
    except (FleetFileError, FleetError, OSError) as exc:
        raise CalibrationError(
            f"the particles are calibrated, but the fleet file could not record it: {exc}"
        ) from None
    return notes


def readings_meta(kind: str, radio: str, lamp_height_cm: float, frames: int) -> dict[str, str]:
    return {
        "kind": kind,
        "radio": radio,
        "lamp_height_cm": f"{lamp_height_cm:g}",
        "frames": str(frames),
        "taken": dt.datetime.now(dt.UTC).replace(microsecond=0).isoformat(),
    }
