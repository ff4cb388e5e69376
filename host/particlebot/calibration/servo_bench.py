"""Servo calibration with a person at the bench: the particle holds each of nine pulses while its
radius is measured, then the new table is written, checked and recorded.

The hold is SERVO_HOLD, renewed while the person measures (the firmware lets go by itself when a
hold runs out, so a tool that dies cannot leave the servo straining) and ended whenever this
leaves, Ctrl-C included. Nobody keeps a servo held for ever: after MAX_HOLD_WAIT_S on one point
the tool lets it rest and says how to hold it again.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO

import numpy as np

from particlebot.calibration.photocells import CalibrationError
from particlebot.calibration.prompts import KEEP_ALIVE_S, NobodyAnswers, Prompter, Quit
from particlebot.calibration.servo import (
    POINTS,
    PULSE_MAX,
    PULSE_MIN,
    TABLE_PARAMS,
    ServoTable,
    table_from_measurements,
    target_radii_mm,
    write_order,
)
from particlebot.fleet import FleetError, FleetFileError, updating_fleet
from particlebot.protocol import Param
from particlebot.swarm.api import Swarm
from particlebot.swarm.results import NotConfirmed, ParticlesMissing

HOLD_S = 30
"""Each SERVO_HOLD asks for this long (the firmware holds at most 60 s)..."""
RENEW_S = 10.0
"""...and is sent again this often while the person measures, so it never runs out."""
MAX_HOLD_WAIT_S = 300.0
"""Held this long at one point without an answer, the servo is let go."""
RADIUS_LIMIT_MM = 1000.0
"""No particle is a metre across: a larger answer is a typing mistake (or centimetres)."""


@dataclass
class ServoOutcome:
    particle_id: int
    pulses: list[int]
    radii_mm: list[float]
    old_table: list[int]
    table: ServoTable
    written: bool = False
    notes: list[str] = field(default_factory=list)


class ServoBench:
    """One particle's servo table, measured point by point."""

    def __init__(
        self,
        swarm: Swarm,
        particle_id: int,
        prompter: Prompter,
        out: TextIO,
        *,
        wait_s: float = 15.0,
    ) -> None:
        self.swarm = swarm
        self.id = particle_id
        self.prompter = prompter
        self.out = out
        self.wait_s = wait_s
        self._held: int | None = None
        self._held_since = 0.0
        self._renew_at = 0.0

    def say(self, text: str) -> None:
        print(text, file=self.out, flush=True)

    # ---- the particle ------------------------------------------------------------------------

    def find(self) -> None:
        try:
            self.swarm.wait_for(ids=[self.id], timeout=self.wait_s)
        except ParticlesMissing as exc:
            raise CalibrationError(
                f"particle {self.id} did not answer ({exc}): check its id and that it is on"
            ) from None

    def read_param(self, param: Param) -> int:
        report = self.swarm.get(param, of=self.id)
        reply = report.replies.get(self.id)
        if reply is None:
            raise CalibrationError(f"particle {self.id} did not answer GET {param.name}")
        return reply.value

    def hold(self, pulse: int) -> None:
        try:
            self.swarm.hold_servo(self.id, pulse, HOLD_S)
        except NotConfirmed as exc:
            raise CalibrationError(str(exc)) from None
        if self._held != pulse:
            self._held_since = self.swarm.now()
        self._held = pulse
        self._renew_at = self.swarm.now() + RENEW_S

    def release(self) -> None:
        """Ends the hold, if one is on; says so when the particle does not confirm it."""
        if self._held is None:
            return
        self._held = None
        try:
            self.swarm.release_servo(self.id)
        except NotConfirmed as exc:
            self.say(f"  {exc}: it lets go by itself within {HOLD_S} s")

    def keep_alive(self) -> None:
        """While the person measures: the radio is looked after, the hold renewed, and ended
        once it has lasted MAX_HOLD_WAIT_S."""
        self.swarm.sleep(KEEP_ALIVE_S)
        if self._held is None:
            return
        now = self.swarm.now()
        if now - self._held_since >= MAX_HOLD_WAIT_S:
            pulse = self._held
            self.release()
            self.say(
                f"\n  {pulse} us held for {MAX_HOLD_WAIT_S / 60:g} min: the servo rests now. "
                "Type r to hold it again, or the radius if you measured it"
            )
        elif now >= self._renew_at:
            self.hold(self._held)

    # ---- the person --------------------------------------------------------------------------

    def measure_point(self, k: int, pulse: int, default_mm: float) -> float | str:
        """Holds pulse and asks for the radius: a number, or b (back), r (hold again)."""
        self.hold(pulse)
        while True:
            answer = self.prompter.ask(
                f"  point {k} of 0-{POINTS - 1}: holding {pulse} us. Radius in mm "
                f"[{default_mm:.1f}]: ",
                self.keep_alive,
            )
            word = answer.lower()
            if word in ("q", "quit"):
                raise Quit
            if word in ("b", "r"):
                return word
            if not answer:
                return default_mm
            try:
                radius = float(answer)
            except ValueError:
                radius = math.nan
            if math.isfinite(radius) and 0 < radius < RADIUS_LIMIT_MM:
                return radius
            self.say(
                f"  '{answer}' is not a radius in mm (0..{RADIUS_LIMIT_MM:g}): type the radius, "
                f"Enter for {default_mm:.1f}, b for the previous point, r to hold again, q to quit"
            )

    def measure(self, pulses: Sequence[int], defaults_mm: Sequence[float]) -> list[float]:
        radii: list[float | None] = [None] * len(pulses)
        k = 0
        while k < len(pulses):
            default = radii[k] if radii[k] is not None else defaults_mm[k]
            assert default is not None
            answer = self.measure_point(k, pulses[k], default)
            if answer == "b":
                k = max(0, k - 1)
            elif isinstance(answer, float):
                radii[k] = answer
                k += 1
        self.release()
        return [r for r in radii if r is not None]

    def review(
        self, pulses: Sequence[int], radii: list[float], targets: Sequence[float]
    ) -> ServoTable:
        """Shows the points; the person writes the table, measures a point again, or quits. A
        table that is not monotonic can only be measured again (CalibrationError when nobody
        can answer)."""
        while True:
            self.say("  point  pulse us  radius mm")
            for k, (pulse, radius) in enumerate(zip(pulses, radii, strict=True)):
                self.say(f"  {k:>5}  {pulse:>8}  {radius:>9.1f}")
            problem: str | None = None
            table: ServoTable | None = None
            try:
                table = table_from_measurements(pulses, radii, targets)
            except CalibrationError as exc:
                problem = str(exc)
            if problem is not None:
                self.say(f"  {problem}")
                question = f"  Point to measure again (0-{POINTS - 1}), or q to quit: "
            else:
                assert table is not None
                self.say(f"  new table: {', '.join(map(str, table.pulses))} us")
                question = (
                    f"  Enter writes it; a point (0-{POINTS - 1}) measures it again; q quits "
                    "without writing: "
                )
            try:
                answer = self.prompter.ask(question, self.keep_alive).lower()
            except NobodyAnswers:
                if problem is not None:
                    raise CalibrationError(f"{problem}; nothing was written") from None
                raise
            if answer in ("q", "quit"):
                raise Quit
            if not answer and table is not None:
                return table
            if answer.isdigit() and int(answer) < POINTS:
                k = int(answer)
                while True:
                    result = self.measure_point(k, pulses[k], radii[k])
                    if isinstance(result, float):
                        radii[k] = result
                        break
                self.release()

    # ---- the table ---------------------------------------------------------------------------

    def write(self, old: Sequence[int], new: Sequence[int]) -> None:
        """SET_PARAM each point that changes, in an order the firmware's check accepts, then
        reads the table back."""
        for k, value in write_order(old, new):
            try:
                self.swarm.set(TABLE_PARAMS[k], value, to=self.id)
            except NotConfirmed as exc:
                raise CalibrationError(
                    f"writing the table: {exc} (points written so far stay)"
                ) from None
        back = [self.read_param(param) for param in TABLE_PARAMS]
        if back != list(new):
            raise CalibrationError(f"particle {self.id} reads back {back}, not {list(new)}")


def default_pulses(table: Sequence[int]) -> list[int]:
    """Where to hold: the particle's own table, or nine even steps across it when two of its
    points share a pulse (each point needs a pulse of its own)."""
    if len(set(table)) == POINTS:
        return list(table)
    low, high = min(table), max(table)
    if low == high:
        low, high = max(PULSE_MIN, low - 400), min(PULSE_MAX, high + 400)
    return [round(low + k * (high - low) / (POINTS - 1)) for k in range(POINTS)]


def calibrate_servo(
    bench: ServoBench, *, pulses: Sequence[int] | None, fleet_path: Path | None
) -> ServoOutcome:
    """The whole calibration: read the particle's table and radii, measure, review, write,
    record. The hold ends however this ends."""
    bench.find()
    try:
        old = [bench.read_param(param) for param in TABLE_PARAMS]
        r_min, r_max = bench.read_param(Param.RADIUS_MIN_UM), bench.read_param(Param.RADIUS_MAX_UM)
        targets = target_radii_mm(r_min, r_max)
        held = list(pulses) if pulses is not None else default_pulses(old)
        bench.say(
            f"Particle {bench.id}: table {', '.join(map(str, old))} us for radii "
            f"{targets[0]:.1f}..{targets[-1]:.1f} mm. Measure each radius (centre to rim) while "
            "the servo holds; Enter takes the value in brackets."
        )
        defaults = _radii_at(held, old, targets)
        radii = bench.measure(held, defaults)
        table = bench.review(held, radii, targets)
    finally:
        bench.release()
    outcome = ServoOutcome(bench.id, held, radii, old, table)
    if table.extrapolated:
        outcome.notes.append(
            f"points {', '.join(map(str, table.extrapolated))} lie outside the radii measured "
            "(extended from the nearest two): measure again with --pulses reaching further"
        )
    bench.write(old, table.pulses)
    outcome.written = True
    if fleet_path is not None:
        outcome.notes += _record(fleet_path, bench.id, table.pulses)
    return outcome


def _radii_at(pulses: Sequence[int], table: Sequence[int], targets: Sequence[float]) -> list[float]:
    """What the old table claims each held pulse gives: the prompts' defaults."""
    order = np.argsort(table, kind="stable")
    xs = np.asarray(table, dtype=float)[order]
    ys = np.asarray(targets, dtype=float)[order]
    return [float(np.interp(pulse, xs, ys)) for pulse in pulses]


def _record(fleet_path: Path, particle_id: int, table: Sequence[int]) -> list[str]:
    try:
        with updating_fleet(fleet_path) as fleet:
            record = fleet.get(particle_id)
            if record is None:
                return [f"particle {particle_id} is not in {fleet_path}: not recorded there"]
            record.calibration.update(
                {param.name: value for param, value in zip(TABLE_PARAMS, table, strict=True)}
            )
    except (FleetFileError, FleetError, OSError) as exc:
        raise CalibrationError(
            f"the particle has its new table, but the fleet file could not record it: {exc}"
        ) from None
    return []
