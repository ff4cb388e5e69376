"""The calibration bench's swarm: opened on a radio (a simulation stepped by the bench), which
particles it calibrates, who places them, and the readings of a line of them (Fig. S5)."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TextIO

from particlebot.calibration.bench import Bench, readings_meta
from particlebot.calibration.photocells import CalibrationError
from particlebot.calibration.placements import (
    PersonPlacer,
    Placement,
    Placer,
    SimulatedPlacer,
    trials,
)
from particlebot.calibration.prompts import Prompter
from particlebot.calibration.readings import Readings, ReadingsWriter
from particlebot.fleet import DEFAULT_FLEET_FILE
from particlebot.radio import parse_radio_url
from particlebot.swarm.api import SIMULATED_SCHEMES, Swarm
from particlebot.swarm.results import ParticlesMissing


def fleet_path(given: str | Path | None) -> Path | None:
    """The fleet file given, else ./fleet.toml when there is one, else none."""
    if given is not None:
        return Path(given)
    return DEFAULT_FLEET_FILE if DEFAULT_FLEET_FILE.exists() else None


def simulated(radio: str) -> bool:
    """Whether a radio URL names a simulated swarm (its particles are placed by the tool)."""
    return parse_radio_url(radio).scheme in SIMULATED_SCHEMES


@contextmanager
def opened(
    radio: str, log_dir: Path, *, fsync: bool, fleet: Path | None, out: TextIO
) -> Iterator[Swarm]:
    """The swarm on radio: a simulation is stepped by the bench (it moves the particles between
    steps). The notes worth reading and the log's path are printed on out on the way out."""
    if not radio:
        raise ValueError(
            "say which radio: --radio serial:///dev/ttyUSB0, xbee:///dev/ttyUSB0 or virtual://9"
        )
    swarm = Swarm.open(
        radio,
        log_dir=log_dir,
        fsync=fsync,
        fleet=fleet,
        stepped=True if simulated(radio) else None,
    )
    try:
        yield swarm
    finally:
        for note in swarm.notes():
            if not note.startswith("info"):
                print(f"  {note}", file=out)
        swarm.close()
        if swarm.log_path is not None:
            print(f"Log: {swarm.log_path}", file=out)


def particle_ids(
    swarm: Swarm, radio: str, ids: Sequence[int] | None, count: int | None
) -> list[int]:
    """The particles to calibrate: ids, else the first count heard, else the fleet's, else
    every particle of a simulation (virtual://9: nine)."""
    try:
        if ids:
            swarm.wait_for(ids=list(ids))
            return list(ids)
        if count is None and swarm.fleet is None and simulated(radio):
            target = parse_radio_url(radio).target
            count = int(target) if target.isdigit() else None
        if count is not None:
            heard = sorted(p.id for p in swarm.wait_for(count=count) if p.status is not None)
            return heard[:count]
        if swarm.fleet is not None:
            return [p.id for p in swarm.wait_for()]
    except ParticlesMissing as exc:
        raise CalibrationError(str(exc)) from None
    raise ValueError("say which particles: --ids 1-9, --count 9, or a fleet file (--fleet)")


def placer(swarm: Swarm, radio: str, prompter: Prompter, out: TextIO) -> Placer:
    """Who puts the particles where a reading wants them: the tool on a simulated swarm, else a
    person asked at the prompt (the swarm kept polled meanwhile)."""
    if simulated(radio):
        return SimulatedPlacer(swarm.radio, out)
    return PersonPlacer(prompter, out, keep_alive=lambda: swarm.sleep(0.2))


def measure(
    bench: Bench, plan: Sequence[Placement], csv_path: Path, meta: dict[str, str]
) -> Readings:
    """Readings at every placement of plan, each row written to csv_path as it is taken."""
    writer = ReadingsWriter(csv_path, meta)
    try:
        rows = bench.measure_all(list(plan), writer)
    finally:
        writer.close()
        bench.say(f"Readings: {csv_path}")
    return Readings(rows, meta, csv_path)


def measure_line(
    bench: Bench,
    ids: Sequence[int],
    positions_cm: Sequence[float],
    count: int,
    radio: str,
    lamp_height_cm: float,
    csv_path: Path,
) -> Readings:
    """Fig. S5's line of particles at positions_cm, count times over, each particle's readings
    averaged over the bench's frames."""
    plan = trials(list(ids), list(positions_cm), count)
    meta = readings_meta("check", radio, lamp_height_cm, bench.frames)
    return measure(bench, plan, csv_path, meta)
