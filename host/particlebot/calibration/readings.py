"""Photocell readings at known light, as a CSV: what `calibrate sensors` fits and `calibrate check`
draws, written by both as they measure, or by hand from readings taken some other way.

`# key: value` lines first (what the file is, the lamp's height), then one row per particle and
placement: step, id, distance_cm (the particle's centre from the point under the lamp, along the
floor) or lux (the illuminance a lux meter read at the photocells), frames (how many STATUS
reports were averaged), A0..A5 (each photocell's raw reading, 0..1023, as STATUS reports it),
intensity (the particle's own, calibrated, reading) and faults (STATUS's sensor_faults bits).
Only id, distance_cm or lux, and A0..A5 are required.
"""

from __future__ import annotations

import csv
import math
import statistics
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from particlebot.errors import ParticlebotError
from particlebot.fleet import FIRST_ID, LAST_ID
from particlebot.protocol import Status
from particlebot.sim.world.light import ADC_FULL_SCALE, SENSOR_COUNT

MAGIC = "# particlebot photocell readings"
SENSOR_COLUMNS = tuple(f"A{k}" for k in range(SENSOR_COUNT))
COLUMNS = ("step", "id", "distance_cm", "lux", "frames", *SENSOR_COLUMNS, "intensity", "faults")


class ReadingsError(ParticlebotError, ValueError):
    """A readings file that cannot be used; the message names the file, the line and why."""


@dataclass(frozen=True)
class Reading:
    """One particle's photocells at one placement, averaged over `frames` STATUS reports."""

    step: int
    id: int
    distance_cm: float | None
    lux: float | None
    sensors: tuple[float, ...]
    intensity: float | None = None
    faults: int = 0
    frames: int = 1

    def healthy(self, k: int) -> bool:
        """Whether photocell k read something a fit can use: not flagged stuck, not at 0 or
        1023 (where the divider says nothing about the resistance)."""
        value = self.sensors[k]
        return not (self.faults >> k) & 1 and 0 < value < ADC_FULL_SCALE

    def raw_intensity(self) -> float | None:
        """The mean of the healthy photocells' raw readings: the intensity an uncalibrated
        particle reports (the firmware's defaults leave every reading as it is)."""
        values = [self.sensors[k] for k in range(SENSOR_COUNT) if self.healthy(k)]
        return statistics.fmean(values) if values else None


@dataclass
class Readings:
    """A readings file's header and rows."""

    rows: list[Reading]
    meta: dict[str, str] = field(default_factory=dict)
    path: Path | None = None

    @property
    def lamp_height_cm(self) -> float | None:
        text = self.meta.get("lamp_height_cm")
        try:
            value = float(text) if text is not None else math.nan
        except ValueError:
            return None
        return value if math.isfinite(value) and value > 0 else None

    def ids(self) -> list[int]:
        return sorted({row.id for row in self.rows})

    def of(self, particle_id: int) -> list[Reading]:
        return [row for row in self.rows if row.id == particle_id]


def from_statuses(
    step: int,
    particle_id: int,
    statuses: Sequence[Status],
    *,
    distance_cm: float | None = None,
    lux: float | None = None,
) -> Reading:
    """The mean of several STATUS reports of one particle at one placement."""
    if not statuses:
        raise ValueError("no STATUS reports to average")
    sensors = tuple(
        statistics.fmean(status.sensors[k] for status in statuses) for k in range(SENSOR_COUNT)
    )
    faults = 0
    for status in statuses:
        faults |= status.sensor_faults
    return Reading(
        step=step,
        id=particle_id,
        distance_cm=distance_cm,
        lux=lux,
        sensors=sensors,
        intensity=statistics.fmean(status.intensity for status in statuses),
        faults=faults,
        frames=len(statuses),
    )


def _number(value: float | None, digits: int) -> str:
    return "" if value is None else f"{value:.{digits}f}"


def header_lines(meta: dict[str, str]) -> list[str]:
    return [MAGIC, *(f"# {key}: {value}" for key, value in meta.items())]


def row_cells(row: Reading) -> list[str]:
    return [
        str(row.step),
        str(row.id),
        _number(row.distance_cm, 2),
        _number(row.lux, 3),
        str(row.frames),
        *(_number(value, 2) for value in row.sensors),
        _number(row.intensity, 2),
        str(row.faults),
    ]


class ReadingsWriter:
    """Writes a readings file row by row, each flushed: a calibration interrupted half way keeps
    what it measured."""

    def __init__(self, path: Path, meta: dict[str, str]) -> None:
        self.path = path
        path.parent.mkdir(parents=True, exist_ok=True)
        self._file = path.open("w", encoding="utf-8", newline="")
        self._csv = csv.writer(self._file, lineterminator="\n")
        self._file.write("\n".join(header_lines(meta)) + "\n")
        self._csv.writerow(COLUMNS)
        self._file.flush()

    def write(self, rows: Iterable[Reading]) -> None:
        for row in rows:
            self._csv.writerow(row_cells(row))
        self._file.flush()

    def close(self) -> None:
        self._file.close()


def write_readings(readings: Readings, path: Path) -> None:
    writer = ReadingsWriter(path, readings.meta)
    try:
        writer.write(readings.rows)
    finally:
        writer.close()


def read_readings(path: Path) -> Readings:
    """A readings file; ReadingsError (one line: file, line, what is wrong) when unusable."""
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ReadingsError(f"no such readings file: {path}") from None
    except IsADirectoryError:
        raise ReadingsError(f"{path} is a folder, not a readings file (CSV)") from None
    except OSError as exc:
        raise ReadingsError(f"cannot read {path}: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise ReadingsError(f"{path} is not a text (CSV) file") from None
    meta: dict[str, str] = {}
    lines = text.splitlines()
    first_data = 0
    for number, line in enumerate(lines):
        if not line.startswith("#"):
            first_data = number
            break
        key, colon, value = line[1:].partition(":")
        if colon:
            meta[key.strip()] = value.strip()
    else:
        first_data = len(lines)
    body = lines[first_data:]
    if not body or not body[0].strip():
        raise ReadingsError(f"{path}: no column header (id, distance_cm or lux, A0..A5)")
    table = csv.reader(body)
    header = [name.strip() for name in next(table)]
    missing = [name for name in ("id", *SENSOR_COLUMNS) if name not in header]
    if missing or ("distance_cm" not in header and "lux" not in header):
        need = ", ".join(missing) if missing else "distance_cm or lux"
        raise ReadingsError(f"{path}:{first_data + 1}: the header lacks {need}")
    rows = []
    for offset, cells in enumerate(table, start=2):
        if not any(cell.strip() for cell in cells):
            continue
        where = f"{path}:{first_data + offset}"
        if len(cells) != len(header):
            raise ReadingsError(f"{where}: {len(cells)} cells where the header names {len(header)}")
        rows.append(_row(dict(zip(header, (c.strip() for c in cells), strict=True)), where))
    if not rows:
        raise ReadingsError(f"{path}: no readings below the header")
    kinds = {row.lux is None for row in rows}
    if len(kinds) > 1:
        raise ReadingsError(
            f"{path}: some rows give distance_cm and others lux: one file, one kind of light"
        )
    return Readings(rows, meta, path)


def _row(cells: dict[str, str], where: str) -> Reading:
    def number(name: str, *, low: float, high: float = math.inf, optional: bool = False) -> float:
        text = cells.get(name, "")
        if not text and optional:
            return math.nan
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and low <= value <= high):
            raise ReadingsError(f"{where}: {name} must be a number {low:g}..{high:g}, not '{text}'")
        return value

    particle_id = number("id", low=FIRST_ID, high=LAST_ID)
    if particle_id != int(particle_id):
        raise ReadingsError(f"{where}: id must be a whole number, not '{cells['id']}'")
    distance = number("distance_cm", low=0, optional=True)
    lux = number("lux", low=0, optional=True)
    if math.isnan(distance) == math.isnan(lux):
        raise ReadingsError(f"{where}: give distance_cm or lux (one of them) for every row")
    if lux == 0:
        raise ReadingsError(f"{where}: lux must be above 0")
    intensity = number("intensity", low=0, high=ADC_FULL_SCALE, optional=True)
    return Reading(
        step=int(number("step", low=0, optional=True) if cells.get("step") else 0),
        id=int(particle_id),
        distance_cm=None if math.isnan(distance) else distance,
        lux=None if math.isnan(lux) else lux,
        sensors=tuple(number(name, low=0, high=ADC_FULL_SCALE) for name in SENSOR_COLUMNS),
        intensity=None if math.isnan(intensity) else intensity,
        faults=int(number("faults", low=0, high=(1 << SENSOR_COUNT) - 1, optional=True) or 0)
        if cells.get("faults")
        else 0,
        frames=int(number("frames", low=1, optional=True)) if cells.get("frames") else 1,
    )
